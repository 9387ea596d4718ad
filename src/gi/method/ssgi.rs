//! Screen-space diffuse gathering over a depth/normal/colour pyramid, unlimited bounces by
//! feedback over frames, and screen-space reflections on glossy materials; no voxels (Oetke
//! 2017 §2.3, §5.1–5.4). Passes: `ssgi` (`ssgi_*`), `ssgi_reflect`, `ssgi_brdf_lut`.

use super::super::ssgi::Ssgi;
use super::super::ssgi_reflect::Ssr;
use super::super::GiSettings;
use super::{EmitterReach, MethodSpec, Refusal};

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "ssgi",
    description: "Screen-space diffuse gathering over a depth/normal/colour pyramid, unlimited \
                  bounces by feedback over frames; no voxels (Oetke 2017 §2.3, §5.1–5.3)",
    summary: "screen-space GI",
    // Feedback adds a bounce per frame.
    accumulates: true,
    temporal: false,
    needs_voxels: false,
    reads_area_light_maps: false,
    // The gather reads the frame's lit colour, emission included, so it sees the emitters the
    // camera sees; it has no ray that leaves the scene, so no environment.
    brings_emitters: EmitterReach::OnScreen,
    brings_environment: false,
    attribute_volumes: |_, _| false,
    material_volume: |_| false,
    // No voxels: transparent layers get direct light only.
    transparent_indirect: |_| None,
    history: |s, size, glossy| {
        if s.ssgi.ssr && glossy {
            vec![Ssgi::history_desc(size), Ssr::history_desc(size)]
        } else {
            vec![Ssgi::history_desc(size)]
        }
    },
    filter_tile: |_| [1, 1],
    multiview_blocker: Some("--gi ssgi keeps one history and one previous camera"),
    orthographic_blocker: Some(Refusal {
        what: "--gi ssgi",
        why: "screen-space GI's patch areas, reflection rays and history assume a pinhole \
              camera's depth",
        instead: "choose another --gi method (hemisphere, pathtrace, vpl)",
    }),
    sweep_keys: &[
        "gi.filter_radius",
        "gi.filter_passes",
        "gi.filter",
        "gi.accumulate_frames",
        "gi.ssgi_resolution",
        "gi.ssgi_samples",
        "gi.ssgi_mips",
        "gi.ssr_rays",
    ],
    // Not in the sweep's default list (`--methods` adds it), as before the registry.
    swept_by_default: false,
    plot_colour: "#9467bd",
    describe: |gi| {
        format!(
            "ssgi, 1/{} resolution, {} samples, {}",
            gi.ssgi.resolution.divisor(),
            gi.ssgi.samples,
            super::filter_label(gi)
        )
    },
    panel: |ui, gi, _| ssgi_controls(ui, gi),
    build: |ctx, settings, target| Ok(Box::new(Ssgi::new(ctx, settings.ssgi, target)?)),
};

/// The screen-space GI's parameters (Oetke 2017 §5.1–5.3): resolution, samples, mips,
/// feedback.
fn ssgi_controls(ui: &mut egui::Ui, gi: &mut GiSettings) {
    use crate::panel_keys::{key_checkbox, key_choice, key_slider};
    key_choice(ui, gi, "gi.ssgi_resolution", "GI resolution");
    key_slider(
        ui,
        gi,
        "gi.ssgi_samples",
        (8.0, 256.0),
        true,
        "samples / texel / level",
    );
    key_choice(ui, gi, "gi.ssgi_mips", "depth and normal mips");
    key_checkbox(ui, gi, "gi.ssgi_feedback", "feedback bounces");
    key_choice(ui, gi, "gi.ssr_rays", "reflection rays");
    key_slider(
        ui,
        gi,
        "gi.ssgi_history_weight",
        (0.0, 0.99),
        false,
        "history weight τ",
    );
}

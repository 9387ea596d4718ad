//! Virtual point lights from the reflective light maps, B bounces, interleaved sampling with
//! voxel visibility and the geometry-aware filter (Thiedemann 2010 Ch. 7). Passes: `vpl`,
//! `gi_vpl_emit`.

use super::super::vpl::VplPasses;
use super::super::GiSettings;
use super::{EmitterReach, LayerIndirect, MethodSpec};

pub(super) static SPEC: MethodSpec = MethodSpec {
    name: "vpl",
    description: "Virtual point lights from the reflective light maps, B bounces, interleaved \
                  sampling with voxel visibility and the geometry-aware filter (Thiedemann \
                  2010 Ch. 7)",
    summary: "virtual point lights",
    accumulates: false,
    // Each frame takes the next VPLs of the Halton sequence (`halton_start`).
    temporal: true,
    needs_voxels: true,
    reads_area_light_maps: false,
    // The emitter VPLs (`gi_vpl_emit`) carry the emitters' light; a VPL starts at a light, so no
    // VPL brings the environment.
    brings_emitters: EmitterReach::All,
    brings_environment: false,
    // Bounces after the first, and the emitters' rays, read albedo and normal at their voxel
    // hits.
    attribute_volumes: |s, scene| {
        s.vpl.bounces > 1
            || scene.has_emission()
            || scene.lights.iter().any(crate::scene::Light::is_area)
    },
    // Glossy hits of the bounces and the emitter rays.
    material_volume: |_| true,
    // Every interleaved set of the frame's VPLs (`oit_gather_vpl`).
    transparent_indirect: |_| Some(LayerIndirect::Vpls),
    history: |_, _, _| Vec::new(),
    // Each pixel of an N×M tile shades one VPL set (interleaved sampling, §7.2).
    filter_tile: |s| s.vpl.pattern,
    multiview_blocker: None,
    orthographic_blocker: None,
    sweep_keys: &[
        "gi.normal_offset_voxels",
        "gi.ray_offset_voxels",
        "gi.filter_radius",
        "gi.filter_passes",
        "gi.filter",
        "gi.start_level",
        "gi.max_iterations",
        "gi.light_map_resolution",
        "gi.vpls",
        "gi.vpl_pattern",
        "gi.vpl_d_min_voxels",
        "gi.vpl_bounces",
        "gi.vpl_visibility",
        "gi.vpl_normalize",
        "gi.vpl_spot_sampling",
        "gi.vpl_shading",
        "gi.temporal",
        "gi.temporal_frames",
    ],
    swept_by_default: true,
    plot_colour: "#2ca02c",
    describe: |gi| {
        format!(
            "vpl, {} per set, {}×{} sets, {} bounces, {}",
            gi.vpl.per_set,
            gi.vpl.pattern[0],
            gi.vpl.pattern[1],
            gi.vpl.bounces,
            super::filter_label(gi)
        )
    },
    panel: |ui, gi, _| {
        vpl_controls(ui, gi);
        super::temporal_controls(ui, gi);
    },
    build: |ctx, settings, target| Ok(Box::new(VplPasses::new(ctx, settings, target)?)),
};

/// The VPL method's parameters (Thiedemann 2010, Ch. 7): VPLs per set, pattern, bounces,
/// d_min, the glossy receivers' roughness floor, visibility, normalization, spot sampling.
fn vpl_controls(ui: &mut egui::Ui, gi: &mut GiSettings) {
    use crate::panel_keys::{key_choice, key_pair_sliders, key_slider};
    key_slider(ui, gi, "gi.vpls", (1.0, 64.0), true, "VPLs / set / light");
    key_pair_sliders(ui, gi, "gi.vpl_pattern", (1, 8), ["pattern N", "pattern M"]);
    key_slider(ui, gi, "gi.vpl_bounces", (1.0, 8.0), false, "bounces");
    key_slider(
        ui,
        gi,
        "gi.vpl_d_min_voxels",
        (0.0, 64.0),
        false,
        "d_min (voxel diagonals)",
    );
    key_slider(
        ui,
        gi,
        "gi.vpl_min_roughness",
        (0.0, 1.0),
        false,
        "glossy receivers' min. roughness",
    );
    key_choice(ui, gi, "gi.vpl_visibility", "visibility");
    key_choice(ui, gi, "gi.vpl_normalize", "normalize by");
    key_choice(ui, gi, "gi.vpl_spot_sampling", "spot VPLs");
    key_choice(ui, gi, "gi.vpl_shading", "shading");
    // Drawing the VPLs is a view of the viewer, not a setting of the method: no key.
    ui.checkbox(&mut gi.vpl.show, "show VPLs");
}

//! The viewer's stereo view (`voxgi view --stereo MODE`, the panel's "Stereo" section): both
//! eyes rendered in the frame graph, packed by `stereo_pack` and presented.
//!
//! **Fitting.** The packed image fills the scene area right of the panel pixel for pixel
//! (no scaling, so row- and column-interleaved and checkerboard packings keep their texel
//! pattern on the display): each eye is the area's size, or for side-by-side-full half its
//! width (rounded down; a column of the area stays dark on odd widths).
//!
//! **Renderers.** Turning stereo on makes a new renderer ([`StereoRenderers::new`]): one
//! [`Renderer::new_stereo`] of both eyes on the one-frame or multiview path, or where that
//! cannot run ([`crate::render::multiview_blocker`]) two mono renderers, one per eye, in the
//! same frame graph (two-pass); the panel prints why. Eye separation and convergence change
//! the eyes' cameras from the next frame on, without a new renderer.

use crate::graph::{ImageHandle, RenderGraph};
use crate::limits;
use crate::post::{StereoMode, StereoPackPass};
use crate::render::{RenderError, RenderSettings, Renderer, StereoPath, StereoRenderers};
use crate::scene::{Scene, StereoRig};
use crate::vk::{vk, Context, Sampler};

/// What the panel's stereo section edits (and `voxgi view --stereo …` starts with).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoControls {
    /// The packing; `None`: one view (mono).
    pub mode: Option<StereoMode>,
    pub rig: StereoRig,
    /// The path asked for; one-frame and multiview fall back to two-pass where they cannot
    /// run.
    pub path: StereoPath,
}

impl StereoControls {
    /// Mono, with the parallax `--stereo` would start with: the default eye separation and
    /// the convergence on the centre of `scene`'s bounding box.
    pub fn off(scene: &Scene, time_s: f32) -> Self {
        Self {
            mode: None,
            rig: StereoRig {
                convergence_m: crate::render::default_convergence_m(scene, time_s),
                ..StereoRig::default()
            },
            path: StereoPath::default(),
        }
    }
}

/// Every packing the panel offers.
const MODES: [StereoMode; 11] = [
    StereoMode::AnaglyphTrue,
    StereoMode::AnaglyphGray,
    StereoMode::AnaglyphColor,
    StereoMode::AnaglyphHalfColor,
    StereoMode::AnaglyphDubois,
    StereoMode::SideBySide,
    StereoMode::SideBySideFull,
    StereoMode::TopBottom,
    StereoMode::RowInterleaved,
    StereoMode::ColumnInterleaved,
    StereoMode::Checkerboard,
];

const PATHS: [StereoPath; 3] = [
    StereoPath::OneFrame,
    StereoPath::Multiview,
    StereoPath::TwoPass,
];

/// The size of each eye's image whose packing with `mode` fits `area` pixel for pixel (the
/// area itself for mono): half the width for side-by-side-full, the area otherwise; at least
/// 1×1.
pub fn eye_size(mode: Option<StereoMode>, (w, h): (u32, u32)) -> (u32, u32) {
    match mode {
        Some(StereoMode::SideBySideFull) => ((w / 2).max(1), h.max(1)),
        _ => (w.max(1), h.max(1)),
    }
}

/// The stereo state of a running viewer: the right eye's renderer on the two-pass path, the
/// packing pass, and what ran.
pub struct ViewerStereo {
    /// The controls this state was built for (a change of mode on/off or of path needs a new
    /// one; separation and convergence are taken every frame).
    pub built_for: StereoControls,
    /// The right eye on the two-pass path (the viewer's renderer is then the left eye's).
    right: Option<Renderer>,
    /// The path that runs and, where it is not the one asked for, why.
    pub path: StereoPath,
    pub fallback: Option<String>,
    pack: StereoPackPass,
    // Held for `pack`, which was given its raw handle.
    _sampler: Sampler,
}

impl ViewerStereo {
    /// The renderer(s) for `controls` (stereo on) at `settings` (each eye's size): returns
    /// the viewer's renderer (both eyes, or the left) and the stereo state.
    pub fn build(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        controls: StereoControls,
    ) -> Result<(Renderer, Self), RenderError> {
        let pair = StereoRenderers::new(ctx, scene, settings, controls.rig, controls.path)?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let pack = StereoPackPass::new(ctx, sampler.raw)?;
        let state = Self {
            built_for: controls,
            right: pair.right,
            path: pair.path,
            fallback: pair.fallback,
            pack,
            _sampler: sampler,
        };
        Ok((pair.primary, state))
    }

    /// Whether `controls` need a new renderer: stereo turned off, or another path asked for.
    pub fn outdated(&self, controls: &StereoControls) -> bool {
        controls.mode.is_none() || controls.path != self.built_for.path
    }

    /// One line for the panel and the log: the path that runs, and why, if it falls back.
    pub fn describe(&self) -> String {
        match &self.fallback {
            Some(why) => format!(
                "stereo: two-pass ({} falls back: {why})",
                self.built_for.path.name()
            ),
            None => format!("stereo: {}", self.path.name()),
        }
    }

    /// Prepares the next frame of `scene` (its camera between the eyes) with `settings` and
    /// the controls' parallax.
    pub fn prepare(
        &mut self,
        primary: &mut Renderer,
        scene: &Scene,
        settings: &RenderSettings,
        controls: &StereoControls,
    ) -> Result<(), RenderError> {
        if let Some(right) = &mut self.right {
            right.settings = settings.clone();
        }
        crate::render::prepare_stereo_pair(primary, self.right.as_mut(), controls.rig, scene)
    }

    /// Writes the right eye's renderer's frame slot (two-pass; the viewer writes its own).
    pub fn write_frame(&mut self, slot: usize) {
        if let Some(right) = &mut self.right {
            right.write_frame(slot);
        }
    }

    /// Declares both eyes and their packing with `mode`; returns the packed image and its
    /// size.
    pub fn declare(
        &self,
        primary: &Renderer,
        g: &mut RenderGraph,
        mode: StereoMode,
    ) -> (ImageHandle, (u32, u32)) {
        let [left, right] = crate::render::declare_stereo_pair(primary, self.right.as_ref(), g);
        let eye = (primary.settings.width, primary.settings.height);
        let packed = self.pack.declare(g, (left.ldr, right.ldr), mode, eye);
        (packed, mode.packed_size(eye))
    }
}

/// The panel's stereo section: the packing (off or a mode), the path, eye separation and
/// convergence (ranges from [`limits`]); `status` is the path that runs or why it fell back.
/// Adds where the packing combo and, while it is open, its entries were drawn to `spots`
/// ("stereo packing", "stereo packing: NAME"), each a name and a rectangle in points as the
/// panel's `Spot`s are (the panel calls this section, so it cannot be named from here).
pub fn panel_section(
    ui: &mut egui::Ui,
    c: &mut StereoControls,
    status: Option<&str>,
    spots: &mut Vec<(String, egui::Rect)>,
) {
    let label = |m: Option<StereoMode>| m.map_or_else(|| "off".to_owned(), StereoMode::name);
    let combo = egui::ComboBox::from_label("packing")
        .selected_text(label(c.mode))
        .show_ui(ui, |ui| {
            for m in [None].into_iter().chain(MODES.map(Some)) {
                let entry = ui.selectable_value(&mut c.mode, m, label(m));
                spots.push((format!("stereo packing: {}", label(m)), entry.rect));
            }
        });
    spots.push(("stereo packing".into(), combo.response.rect));
    if c.mode.is_none() {
        return;
    }
    egui::ComboBox::from_label("path")
        .selected_text(c.path.name())
        .show_ui(ui, |ui| {
            for p in PATHS {
                ui.selectable_value(&mut c.path, p, p.name());
            }
        });
    ui.add(
        egui::Slider::new(
            &mut c.rig.separation_m,
            limits::STEREO_SEPARATION_M.slider(0.0, 1.0),
        )
        .text("eye separation m"),
    );
    ui.add(
        egui::Slider::new(
            &mut c.rig.convergence_m,
            limits::STEREO_CONVERGENCE_M.slider(0.05, 1000.0),
        )
        .logarithmic(true)
        .text("convergence m"),
    );
    if let Some(s) = status {
        ui.label(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_packing_of_the_eyes_fits_the_area() {
        for area in [(2, 1), (3, 7), (127, 64), (640, 360)] {
            for mode in MODES {
                let eye = eye_size(Some(mode), area);
                let (pw, ph) = mode.packed_size(eye);
                assert!(pw <= area.0 && ph == area.1, "{mode:?} {area:?}");
                // No more than one column is left dark (side-by-side-full on odd widths).
                assert!(area.0 - pw <= 1, "{mode:?} {area:?}");
            }
        }
        // A 1 pixel wide area cannot hold two eyes side by side: the present blit squeezes
        // the 2-pixel packing into it (`Viewer::rebuild` clamps the rectangle).
        assert_eq!(eye_size(Some(StereoMode::SideBySideFull), (1, 4)), (1, 4));
        assert_eq!(eye_size(None, (0, 5)), (1, 5));
    }

    #[test]
    fn mode_names_are_the_flags_values() {
        assert_eq!(StereoMode::AnaglyphDubois.name(), "anaglyph-dubois");
        assert_eq!(StereoMode::SideBySideFull.name(), "side-by-side-full");
        // Every packing is offered once.
        for m in MODES {
            assert_eq!(MODES.iter().filter(|&&x| x == m).count(), 1);
        }
        assert_eq!(
            <StereoMode as clap::ValueEnum>::value_variants().len(),
            MODES.len()
        );
    }
}

//! Opening another scene while the viewer runs: a file dropped on the window
//! (`WindowEvent::DroppedFile`) or the panel's "Open scene" section (a path field and "Open").
//!
//! The scene is loaded by the command line's own code (`SceneOpener`, which `voxgi view`
//! hands to [`super::run`]): the same loader, the same checks and this run's other flags, so
//! a scene opens here exactly as `voxgi view SCENE …` would start with it. Its renderer is
//! made while the old scene still shows; only when both succeed does the viewer switch
//! (after the frames in flight finished). Anything that fails leaves the scene shown as it
//! was and puts the message (file, line or field) in the panel and the log.

use super::{AppError, Viewer, ViewerOptions};
use crate::scene::Scene;
use crate::vk::{vk, Context};
use std::time::Instant;
use winit::window::Window;

/// Why a scene was not opened: the loader's message, which names the file and the line or
/// field, and says what to do.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct OpenError(pub String);

/// Loads a scene named as `voxgi view` takes it (a built-in name, a TOML scene, a glTF/OBJ
/// model) with the viewer's options for it: what the command line would start with.
pub type SceneOpener<'a> = dyn Fn(&str) -> Result<(Scene, ViewerOptions), OpenError> + 'a;

/// The panel's "Open scene" section.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OpenControls {
    /// The scene shown (its file, or the built-in's name).
    pub shown: String,
    /// What the path field holds.
    pub path: String,
    /// Set by "Open", Enter in the field or a dropped file: the viewer opens `path` before
    /// its next frame and clears it.
    pub requested: bool,
    /// Why the last scene asked for was not opened (shown under the field).
    pub error: String,
}

impl OpenControls {
    pub fn showing(shown: String) -> Self {
        Self {
            shown,
            ..Default::default()
        }
    }
}

/// Draws the "Open scene" section; adds where the path field and the button landed to `spots`
/// ("open path", "open button"; the panel's `Spot`s, written out so that this module does not
/// import the panel that calls it).
pub fn panel_section(
    ui: &mut egui::Ui,
    o: &mut OpenControls,
    spots: &mut Vec<(String, egui::Rect)>,
) {
    ui.label(format!("showing {}", o.shown));
    let field = ui.add(
        egui::TextEdit::singleline(&mut o.path)
            .hint_text("scene file, model or built-in name")
            .desired_width(f32::INFINITY),
    );
    let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    let button = ui
        .button("Open")
        .on_hover_text("or drop a scene file on the window");
    if (button.clicked() || entered) && !o.path.trim().is_empty() {
        o.requested = true;
    }
    spots.push(("open path".into(), field.rect));
    spots.push(("open button".into(), button.rect));
    if !o.error.is_empty() {
        ui.colored_label(ui.visuals().error_fg_color, &o.error);
    }
}

impl Viewer {
    /// Opens `arg` in place of the scene shown, for a swapchain of `extent`. The old scene's
    /// unsaved edits, its recorded camera keys and the panel's settings go with it: the new
    /// scene starts as the command line would start it. Errors a user can cause (the
    /// loader's, a renderer the scene cannot have) leave everything as it was and are
    /// shown; only a failure of the device itself ends the viewer.
    pub(super) fn open_scene(
        &mut self,
        ctx: &Context,
        window: &Window,
        extent: vk::Extent2D,
        opener: &SceneOpener,
        arg: &str,
    ) -> Result<(), AppError> {
        let started = Instant::now();
        log::info!("opening scene {arg}");
        let (scene, opts) = match opener(arg) {
            Ok(opened) => opened,
            Err(e) => {
                self.refuse_open(arg, &e.to_string());
                return Ok(());
            }
        };
        let mut next = Viewer::with_swapchain(window, scene, &opts, None);
        next.resolve_stereo_path(ctx);
        // What belongs to the window rather than the scene, for the renderer's size.
        next.panel_px = self.panel_px;
        next.window_px = self.window_px;
        // The new renderer is made while the old one still shows (a scene the device cannot
        // render leaves the old one): both are held for that moment.
        if let Err(e) = next.update_renderer(ctx, extent) {
            // Whatever it made goes once the frames in flight are done with nothing of it.
            drop(next);
            self.refuse_open(arg, &e.to_string());
            return Ok(());
        }
        // The frames in flight finish before the old scene's objects are released.
        if let Some(fl) = self.frame_loop.as_mut() {
            fl.finish(ctx)?;
        }
        self.carry_into(&mut next);
        if !next.report.camera_keys.is_empty() {
            log::warn!(
                "the {} camera keys recorded in {} are dropped with it",
                next.report.camera_keys.len(),
                self.controls.open.shown
            );
            next.report.camera_keys.clear();
        }
        next.status = format!("opened {arg} ({} ms)", started.elapsed().as_millis());
        log::info!("{}", next.status);
        *self = next;
        Ok(())
    }

    /// Moves what outlives a scene into `next`: the window's state and swapchain, the
    /// panel's GPU objects and egui state, the frame loop, the report and the scripted run's
    /// progress.
    fn carry_into(&mut self, next: &mut Viewer) {
        next.swapchain = self.swapchain.take();
        next.swapchain_dirty = self.swapchain_dirty;
        next.overlay = self.overlay.take();
        next.frame_loop = self.frame_loop.take();
        next.pick = self.pick.take();
        if let Some(p) = next.pick.as_mut() {
            p.forget();
        }
        // egui's memory (scroll, open sections) and input state stay: the panel is the same.
        next.egui_ctx = self.egui_ctx.clone();
        std::mem::swap(&mut next.egui_state, &mut self.egui_state);
        next.keys = self.keys;
        next.cursor = self.cursor;
        next.ctrl = self.ctrl;
        next.last_frame = self.last_frame;
        next.frame_ms = self.frame_ms;
        next.frame_dt_ms = self.frame_dt_ms;
        next.started = self.started;
        next.report = std::mem::take(&mut self.report);
        next.resize_requested = self.resize_requested;
        next.minimize_script = self.minimize_script;
        next.minimized = self.minimized;
        next.oversized = self.oversized;
        next.refused_px = self.refused_px;
        next.window_gone = self.window_gone;
        next.panel_scroll = self.panel_scroll;
        next.panel_spots = std::mem::take(&mut self.panel_spots);
    }

    /// Leaves the scene shown as it is and says why `arg` was not opened.
    fn refuse_open(&mut self, arg: &str, why: &str) {
        self.controls.open.error = format!("{arg} not opened: {why}");
        log::warn!("{}", self.controls.open.error);
    }
}

//! `voxgi view`: the interactive viewer.

use super::args::GiArgs;
use super::{out, outln, CliError, Global};
use crate::render::RenderSettings;
use crate::voxel::debug_view::{DebugSettings, DebugView};
use std::io::Write;
use std::path::PathBuf;

use crate::app::RECORDED_KEY_SPACING_S;

/// Arguments of `voxgi view`.
#[derive(clap::Args, Clone)]
pub struct ViewArgs {
    /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
    pub scene: Option<String>,
    /// Initial window width and height, pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Start with a voxel debug view instead of the lit image (the panel switches views).
    #[arg(long, value_enum)]
    pub debug: Option<DebugView>,
    /// The object whose atlas the atlas view shows: its name or index in the scene.
    #[arg(long, default_value = "0")]
    pub object: String,
    /// Scripted run (tests): exit after N presented frames, writing --screenshot.
    #[arg(long)]
    pub frames: Option<u64>,
    /// Scripted run: resize the window to WxH halfway through.
    #[arg(long, value_parser = parse_size)]
    pub resize: Option<(u32, u32)>,
    /// Scripted run: minimize the window after FRAME presented frames, restore it after
    /// --restore-after skipped redraws (needs a window manager; under Xvfb e.g. openbox).
    #[arg(long, value_name = "FRAME")]
    pub minimize_at: Option<u64>,
    /// Scripted run: redraws to skip while minimized before restoring the window.
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub restore_after: u64,
    /// Screenshot PNG path (F12 / the panel button; the end of a scripted run).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// The sweep the panel's "best within budget" chooses from (a `voxgi sweep --out` folder,
    /// measured on this device).
    #[arg(long, default_value = "sweep", value_name = "DIR")]
    pub sweep: PathBuf,
    /// Start with the most accurate configuration of --sweep that fits this GPU time to the
    /// image (`voxgi tune`'s choice); the panel's budget starts here too.
    #[arg(long, value_name = "MS")]
    pub budget_ms: Option<f64>,
    /// Where "Save scene" (Ctrl+S) writes the edited scene. Default: the scene's own file
    /// (a built-in scene has none and needs this).
    #[arg(long, value_name = "PATH")]
    pub save: Option<PathBuf>,
    // The initial post-processing (over the scene's `[post]` table); the panel's
    // "Post-processing" section changes it. In the viewer every frame is one TAA frame.
    #[command(flatten)]
    pub post: super::args::PostArgs,
    // The initial shadows (over the scene's `[shadow]` table); the panel's "Shadows" section
    // changes them.
    #[command(flatten)]
    pub shadow: super::args::ShadowArgs,
    // The initial indirect light; the panel changes it.
    #[command(flatten)]
    pub gi: GiArgs,
    // The initial stereo packing and parallax; the panel's "Stereo" section changes them.
    #[command(flatten)]
    pub stereo: super::render::StereoArgs,
    // The initial projection; the panel switches it.
    #[command(flatten)]
    pub camera: super::args::CameraArgs,
}

/// Refuses a `--save` path whose folder does not exist, before the window opens.
fn check_save_path(path: &std::path::Path) -> Result<(), CliError> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    let problem = match dir {
        Some(d) if !d.is_dir() => format!(
            "the folder {} does not exist; create it or save elsewhere",
            d.display()
        ),
        _ if path.is_dir() => format!(
            "that is a folder; give a file name, e.g. {}",
            path.join("edited.toml").display()
        ),
        _ => return Ok(()),
    };
    Err(CliError::SavePath {
        path: path.to_path_buf(),
        problem,
    })
}

/// `WxH` → (W, H), both positive.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not WxH (e.g. 640x480)"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("`{v}` in `{s}` is not a size between 1 and 16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

/// Runs the viewer until its window closes (or a scripted run ends), then prints the camera
/// as a pasteable `[camera]` table and the screenshots written.
pub fn view(global: &Global, args: ViewArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let (scene, opts) = open_scene(global, &args, args.scene.as_deref(), out)?;
    // A scene opened while the viewer runs (dropped on the window, or the panel's "Open")
    // goes through the same loader and checks, with this run's other flags.
    let open = |arg: &str| -> Result<
        (crate::scene::Scene, crate::app::ViewerOptions),
        crate::app::OpenError,
    > {
        let mut said = Vec::new();
        let opened = open_scene(global, &args, Some(arg), &mut said)
            .map_err(|e| crate::app::OpenError(e.to_string()))?;
        for line in String::from_utf8_lossy(&said).lines() {
            log::info!("{line}");
        }
        Ok(opened)
    };
    let report = crate::app::run(scene, &opts, &open)?;
    if let Some(camera) = &report.camera {
        // Pasteable into a scene file, to start there next time (the scene shown at exit).
        out!(
            out,
            "camera at exit:\n{}",
            camera.toml_table(report.origin_m)
        );
    }
    match crate::scene::CameraPath::through_cameras(&report.camera_keys, RECORDED_KEY_SPACING_S) {
        // Pasteable into a scene file, for `voxgi profile --camera-path`.
        Ok(path) => out!(
            out,
            "recorded camera path:\n{}",
            path.toml_table(report.origin_m)
        ),
        Err(e) if !report.camera_keys.is_empty() => {
            outln!(
                out,
                "recorded camera path not printed: `{}`: {}",
                e.field,
                e.problem
            )
        }
        Err(_) => {}
    }
    for p in &report.screenshots {
        outln!(out, "wrote {}", p.display());
    }
    for p in &report.saved {
        outln!(out, "saved scene to {}", p.display());
    }
    if report.skipped_minimized > 0 {
        outln!(
            out,
            "skipped {} frames while minimized",
            report.skipped_minimized
        );
    }
    super::check_teardown(&report.teardown)
}

/// The scene `scene_arg` (a built-in name, a TOML file, a glTF/OBJ model; `None`: the default)
/// and the viewer's options for it under `args`' flags: what `voxgi view SCENE` starts with,
/// and what the running viewer opens. Every check of the command line runs here, before any
/// GPU work; what it prints (the budget's choice) goes to `out`.
fn open_scene(
    global: &Global,
    args: &ViewArgs,
    scene_arg: Option<&str>,
    out: &mut dyn Write,
) -> Result<(crate::scene::Scene, crate::app::ViewerOptions), CliError> {
    let scene = args.camera.load_scene(scene_arg)?;
    // Checked when the viewer starts in the atlas view; the panel may switch to it
    // later, then showing this object if it exists, else the first.
    let object = match scene.find_object(&args.object) {
        Ok(i) => i,
        Err(e) if args.debug == Some(DebugView::Atlas) => return Err(e.into()),
        Err(_) => 0,
    };
    let mut settings = RenderSettings {
        debug: args.debug.map(|view| DebugSettings {
            view,
            object,
            ..Default::default()
        }),
        ..Default::default()
    };
    // The scene's `[post]` table starts the panel's post-processing; the flags override it.
    let post = args
        .gi
        .post(&args.post, &scene, settings.post, settings.tonemap)?;
    (settings.post, settings.tonemap) = (post.post, post.tonemap);
    // The scene's `[shadow]` table, under the flags, starts the panel's shadows ("Save scene"
    // writes them back).
    settings.shadow = args
        .shadow
        .apply(settings.shadow, &scene.shadow, &args.gi.set)?;
    settings.gi = args.gi.settings(&scene)?;
    args.gi.check_sao(&settings.gi)?;
    // `--set voxel.KEY=V` over the scene's `[voxel]`: the grid of every renderer the viewer
    // makes (it voxelizes when something needs voxels, as `render` does).
    let voxel = super::args::VoxelArgs::default().layer(&args.gi.set)?;
    let mut scene = scene;
    scene.voxel = voxel.over(&scene.voxel);
    // The viewer accumulates GI over frames unless the scene or a flag says otherwise
    // (`post.dynamic_gi`; docs/design/dynamic-resolution.md).
    let temporal_set = [&scene.gi, &args.gi.layer()?]
        .iter()
        .any(|l| l.get("gi.temporal").is_some());
    settings.gi = crate::app::viewer_gi(settings.gi, temporal_set, &post.dynres);
    let name = super::sweep::scene_name(scene_arg.unwrap_or(crate::scene::DEFAULT_SCENE));
    if let Some(budget) = args.budget_ms {
        let (row, _, layer) = crate::tune::tune_from_dir(&args.sweep, &name, budget)?;
        settings.gi = crate::scene::schema::apply(settings.gi, &[&layer]);
        outln!(
            out,
            "best within {budget} ms: {} ({:.1} ms to the image, relMSE {:.4}, on {})",
            row.config,
            row.image_ms,
            row.rel_mse,
            row.device
        );
    }
    crate::render::check_render_settings(&settings)?;
    // The panel's parallax starts at the flags' even without --stereo.
    let stereo = crate::app::StereoControls {
        mode: args.stereo.stereo,
        rig: args.stereo.rig(&scene, settings.time_s)?,
        // Resolved against the device when the viewer opens (`ViewerOptions::stereo_path`).
        path: args.stereo.stereo_path.unwrap_or_default(),
    };
    if let Some(path) = &args.save {
        check_save_path(path)?;
    }
    let opts = crate::app::ViewerOptions {
        validation: global.validate,
        device: global.device.clone(),
        width: args.width,
        height: args.height,
        settings,
        frames: args.frames,
        resize_to: args.resize,
        minimize_at: args.minimize_at,
        restore_after: args.restore_after,
        screenshot: args.screenshot.clone(),
        sweep_dir: args.sweep.clone(),
        scene_name: name,
        budget_ms: args.budget_ms.unwrap_or(100.0) as f32,
        dynres: post.dynres,
        stereo: Some(stereo),
        stereo_path: args.stereo.stereo_path,
        save_to: args.save.clone(),
        builtin: crate::scene::builtin_toml(scene_arg.unwrap_or(crate::scene::DEFAULT_SCENE))
            .is_some()
            .then(|| scene_arg.unwrap_or(crate::scene::DEFAULT_SCENE).to_owned()),
    };
    Ok((scene, opts))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gi::GiMethod;
    use clap::Parser as _;

    #[derive(clap::Parser)]
    struct View {
        #[command(flatten)]
        args: ViewArgs,
    }

    #[test]
    fn the_viewer_takes_the_gi_flags() {
        let v = View::try_parse_from(["view", "--gi", "pathtrace", "--gi-bounces", "1"])
            .expect("parses")
            .args;
        let layer = v.gi.layer().expect("in range");
        let s = crate::scene::resolve_gi(&Default::default(), &layer);
        assert_eq!(
            (s.method, s.bounces, layer.get("gi.rays")),
            (GiMethod::Pathtrace, crate::gi::Bounces::Fixed(1), None)
        );
    }

    #[test]
    fn sizes_parse_as_width_x_height_within_limits() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert_eq!(parse_size("16384X1"), Ok((16384, 1)));
        for bad in ["640", "0x480", "640x16385", "ax1", "640x-1"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }
}

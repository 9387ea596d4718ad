//! `voxgi profile` (per-pass GPU times over many frames) and `voxgi graph` (the compiled
//! render graph), for a scene's frame or the render-graph demo frame.

use super::args::FrameArgs;
use super::{out, outln, with_context, CliError, Global};
use crate::demo::Demo;
use crate::graph::GraphExecutor;
use crate::profile::ProfileReport;
use crate::render::{profile_camera_path, profile_scene};
use crate::vk::{Context, MAX_FRAMES_IN_FLIGHT};
use std::io::Write;

/// Arguments of `voxgi profile`.
#[derive(clap::Args, Clone)]
pub struct ProfileArgs {
    /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
    pub scene: Option<String>,
    /// Profile the render-graph demo frame instead of a scene.
    #[arg(long)]
    pub demo: bool,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Frames measured after warm-up.
    #[arg(long, default_value_t = 100)]
    pub frames: usize,
    /// Frames run before measuring.
    #[arg(long, default_value_t = 10)]
    pub warmup: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Fly the camera along the scene's `[camera_path]`: the measured frames are spread
    /// evenly in time over it, so timings are taken along the same flight every time.
    #[arg(long, conflicts_with = "demo")]
    pub camera_path: bool,
    /// Frames measured along the camera path (default: `--frames`).
    #[arg(long, requires = "camera_path")]
    pub path_frames: Option<usize>,
    /// `--stereo MODE`: profile the stereo pair's frame (both eyes, the right eye's passes
    /// marked `[R]`, and the packing), then the mono frame of the same flags in the same run.
    #[command(flatten)]
    pub stereo: super::render::StereoArgs,
}

/// Arguments of `voxgi graph`.
#[derive(clap::Args, Clone)]
pub struct GraphArgs {
    /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
    pub scene: Option<String>,
    /// The render-graph demo frame instead of a scene's frame.
    #[arg(long)]
    pub demo: bool,
    /// Graphviz dot instead of text.
    #[arg(long)]
    pub dot: bool,
    #[command(flatten)]
    pub frame: FrameArgs,
}

/// Runs the frame `--warmup` + `--frames` times and prints the per-pass statistics.
pub fn profile(global: &Global, args: &ProfileArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let frame = &args.frame;
    // The scene and the flags are checked before the device is up.
    let scene = match args.demo {
        true => None,
        false => {
            let scene = frame.camera.load_scene(args.scene.as_deref())?;
            let settings = frame.settings(&scene)?;
            Some((scene, settings))
        }
    };
    let scene_name = args
        .scene
        .clone()
        .unwrap_or_else(|| crate::scene::DEFAULT_SCENE.into());
    let path = match (&scene, args.camera_path) {
        (Some((s, _)), true) => Some(s.camera_path.clone().ok_or(CliError::NoCameraPath {
            command: "voxgi profile --camera-path",
            scene: scene_name.clone(),
        })?),
        _ => None,
    };
    let frames = args.path_frames.unwrap_or(args.frames);
    let stereo = match (&scene, args.stereo.stereo) {
        (Some((s, settings)), Some(_)) if !args.camera_path => {
            args.stereo.settings(s, settings.time_s)?
        }
        (_, Some(_)) => return Err(CliError::StereoProfile),
        _ => None,
    };
    with_context(global, |ctx| {
        let report = if let (Some((scene, settings)), Some(mut stereo)) = (&scene, stereo) {
            let chosen = args.stereo.take_default_path(&ctx.info, &mut stereo);
            let p =
                crate::render::profile_stereo(ctx, scene, settings, stereo, frames, args.warmup)?;
            stereo_report(
                &ctx.info.name,
                (&p, chosen.as_deref()),
                &scene_name,
                settings,
                stereo,
                args.warmup,
            )
        } else if let Some((scene, settings)) = &scene {
            let run = match &path {
                Some(p) => profile_camera_path(ctx, scene, settings, p, frames, args.warmup)?,
                None => profile_scene(ctx, scene, settings, frames, args.warmup)?,
            };
            let mut report = ProfileReport::from_frames(&ctx.info.name, &run.frames, args.warmup)
                .with_setup(&run.setup);
            report.notes.push(("scene".into(), scene_name));
            if let Some(p) = &path {
                let (t0, t1) = p.time_range_s();
                report.notes.push((
                    "camera path".into(),
                    format!(
                        "{frames} frames evenly over {t0}..{t1} s ({} keyframes)",
                        p.keys().len()
                    ),
                ));
            }
            report.notes.push((
                "resolution".into(),
                format!("{}x{}", frame.width, frame.height),
            ));
            if let Some(a) = run.auto_shadow {
                report.notes.push((
                    "shadow resolution".into(),
                    format!(
                        "auto: {r}² (95th percentile of the lit pixels' shadow texels {q:.3} px at \
                         the {p}² probe)",
                        r = a.resolution,
                        q = a.quantile_px_at_probe,
                        p = a.probe_resolution
                    ),
                ));
            }
            report
                .notes
                .push(("transient memory".into(), run.transient_memory.summary()));
            report
                .notes
                .push(("culled passes".into(), run.culled_passes.join(", ")));
            report
        } else {
            profile_demo(ctx, args.frames, args.warmup, frame.width, frame.height)?
        };
        if args.json {
            outln!(out, "{}", serde_json::to_string_pretty(&report)?);
        } else {
            out!(out, "{}", report.table());
        }
        Ok(())
    })
}

/// The stereo frame's statistics (both eyes' passes, the right eye's marked `[R]`), with the
/// mono frame of the same run and their ratio in the notes.
fn stereo_report(
    device: &str,
    (p, chosen): (&crate::render::StereoProfile, Option<&str>),
    scene_name: &str,
    settings: &crate::render::RenderSettings,
    stereo: crate::render::StereoSettings,
    warmup: usize,
) -> ProfileReport {
    let mut report =
        ProfileReport::from_frames(device, &p.stereo.frames, warmup).with_setup(&p.stereo.setup);
    let mono = ProfileReport::from_frames(device, &p.mono.frames, warmup);
    let mode = stereo.mode.name();
    let path = super::render::stereo_path_line(stereo.path, chosen, p.path, p.fallback.as_deref());
    let right: f64 = report
        .passes
        .iter()
        .filter(|s| s.name.ends_with(crate::render::RIGHT_EYE_SUFFIX))
        .map(|s| s.median_ms)
        .sum();
    let (s_ms, m_ms) = (report.frame_median_ms, mono.frame_median_ms);
    // On a shared machine a pass's minimum is the least disturbed measure of it.
    let minima = |r: &ProfileReport| r.passes.iter().map(|p| p.min_ms).sum::<f64>();
    let (s_min, m_min) = (minima(&report), minima(&mono));
    let (e, c) = (stereo.rig.separation_m, stereo.rig.convergence_m);
    let notes = [
        ("scene", scene_name.to_owned()),
        (
            "resolution",
            format!("{}x{} per eye", settings.width, settings.height),
        ),
        (
            "stereo",
            format!("{mode}, path {path}, eye separation {e} m, convergence {c} m"),
        ),
        (
            "mono frame",
            format!(
                "{m_ms:.4} ms median (the same flags without --stereo, its frames taking turns \
                 with the stereo frames, {} at a time)",
                crate::render::PROFILE_ROUND_FRAMES
            ),
        ),
        (
            "stereo vs mono",
            format!(
                "{:.3}× ({:+.4} ms for the second eye and the packing)",
                s_ms / m_ms.max(1e-9),
                s_ms - m_ms
            ),
        ),
        (
            "stereo vs mono, minima",
            format!(
                "{:.3}× (sums of the passes' minimum ms: {s_min:.4} stereo, {m_min:.4} mono)",
                s_min / m_min.max(1e-9)
            ),
        ),
        (
            "right eye's passes [R]",
            format!("{right:.4} ms (sum of their medians)"),
        ),
        ("transient memory", p.stereo.transient_memory.summary()),
        ("culled passes", p.stereo.culled_passes.join(", ")),
    ];
    report
        .notes
        .extend(notes.into_iter().map(|(k, v)| (k.to_owned(), v)));
    report
}

/// The demo frame's statistics, measured like a scene's.
fn profile_demo(
    ctx: &Context,
    frames: usize,
    warmup: usize,
    width: u32,
    height: u32,
) -> Result<ProfileReport, CliError> {
    let demo = Demo::new(ctx, width, height)?;
    let exec = demo.executor(ctx, MAX_FRAMES_IN_FLIGHT)?;
    let measured = crate::graph::run_frames(ctx, &exec, warmup + frames, warmup, |_| {});
    let measured = measured?;
    let c = exec.compiled();
    let mut report = ProfileReport::from_frames(&ctx.info.name, &measured, warmup);
    report
        .notes
        .push(("graph".into(), "demo (4 live passes, 1 culled)".into()));
    report
        .notes
        .push(("resolution".into(), format!("{width}x{height}")));
    report
        .notes
        .push(("transient memory".into(), c.memory.summary()));
    let culled: Vec<&str> = c.culled.iter().map(|&p| c.pass_names[p].as_str()).collect();
    report
        .notes
        .push(("culled passes".into(), culled.join(", ")));
    Ok(report)
}

/// Prints the compiled graph as text or Graphviz dot.
pub fn graph(global: &Global, args: &GraphArgs, out: &mut dyn Write) -> Result<(), CliError> {
    // The scene and the flags are checked before the device is up.
    let scene = match args.demo {
        true => None,
        false => {
            let scene = args.frame.camera.load_scene(args.scene.as_deref())?;
            let settings = args.frame.settings(&scene)?;
            Some((scene, settings))
        }
    };
    with_context(global, |ctx| {
        let mut dump = |exec: &GraphExecutor| -> Result<(), CliError> {
            let c = exec.compiled();
            if args.dot {
                out!(out, "{}", c.dump_dot(exec.graph()));
            } else {
                out!(out, "{}", c.dump_text(exec.graph()));
            }
            Ok(())
        };
        // Whatever fails (compiling, or writing to a closed stdout), everything made is released
        // as it goes out of scope, before the context's teardown check.
        if let Some((scene, settings)) = scene {
            let renderer = crate::render::Renderer::new(ctx, &scene, settings)?;
            dump(&GraphExecutor::new(ctx, renderer.graph(), 1)?)?;
        } else {
            let demo = Demo::new(ctx, args.frame.width, args.frame.height)?;
            dump(&demo.executor(ctx, 1)?)?;
        }
        Ok(())
    })
}

//! `voxgi sweep` (every method over a grid of GI settings on each scene with a reference:
//! GPU times, transient memory and error metrics, as CSV, JSON and plots (SVG and PNG) of
//! error against time per scene; then the ray tests of `voxgi bench traverse` on each scene,
//! as traverse.csv) and `voxgi tune` (from a sweep's CSV, the most accurate
//! configuration within a time budget, as a `[gi]` table).

use super::args::FrameArgs;
use super::{outln, with_context, CliError, Global};
use crate::bench::plot::{pareto_png, pareto_svg};
use crate::bench::sweep::read_rows;
use crate::bench::sweep::{
    configs, downsample, method_name, parse_grid, parse_methods, read_csv, settings_inline,
    tune_from_dir, Config, CsvAppender, SweepError, SweepRow,
};
use crate::bench::sweep_traverse::{
    march_at_99, march_test, missing_tests, other_settings, settings_text, traverse_rows,
    traverse_tests, RadiusContext, TraverseRow,
};
use crate::bench::temporal::{
    lag_after_switch_off, light_path, path_flicker, LightPath, TemporalDesc,
};
use crate::bench::{
    bench_radius, traverse_rays, TraverseBenchDesc, DEFAULT_MARCH_STEPS, DEFAULT_RADII_BOX_UNITS,
};
use crate::eval::HdrImage;
use crate::render::{profile_scene, render_image, RenderSettings};
use crate::scene::{load_scene_arg, Scene};
use crate::stats::median;
use crate::vk::{Context, PassTiming};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `voxgi sweep`.
#[derive(clap::Args, Clone)]
pub struct SweepArgs {
    /// Built-in scenes or TOML scene files, each with a reference `<name>_gi.exr` in
    /// --references (name: the built-in's name or the file's stem), or for the third-party
    /// scenes `<name>_authors.exr` or `<name>.exr` (their authors' scene rendered by Mitsuba).
    /// Default: every built-in and every assets/scenes/*.toml with a `<name>_gi.exr`.
    pub scenes: Vec<String>,
    /// Methods, comma-separated.
    #[arg(long, default_value_t = crate::bench::sweep::default_sweep_methods())]
    pub methods: String,
    /// A key path or a flag of `voxgi render` (without `--`) and its values:
    /// `--grid gi-rays=4,16`, `--grid voxel.resolution=128,256`. Takes the `[gi]` keys the
    /// methods sweep and every `[shadow]`, `[post]` and `[voxel]` key (those apply to every
    /// method). Repeat for more keys; each method runs every combination of the keys that
    /// change it.
    #[arg(long, value_name = "KEY=V1,V2,…")]
    pub grid: Vec<String>,
    /// Output folder: sweep.csv (a row per configuration, written as each finishes),
    /// traverse.csv (a row per scene, ray radius and ray test, written a radius at a time),
    /// sweep.json (both) and <scene>_pareto.svg and .png.
    #[arg(long)]
    pub out: PathBuf,
    /// Image width in pixels (the height follows each reference's aspect); must divide the
    /// references' width, or be a multiple of it (each render is then box-filtered to the
    /// reference's size before scoring).
    #[arg(long, default_value_t = 128)]
    pub size: u32,
    /// Frames profiled per configuration (after --warmup).
    #[arg(long, default_value_t = 20)]
    pub frames: usize,
    /// Frames run before profiling.
    #[arg(long, default_value_t = 3)]
    pub warmup: usize,
    /// Folder of the reference images.
    #[arg(long, default_value = "assets/references")]
    pub references: PathBuf,
    /// Continue the sweep in --out: skip the rows its sweep.csv has.
    #[arg(long)]
    pub resume: bool,
    /// A scene without a reference in --references gets one from Mitsuba 3 (export-mitsuba +
    /// --reference-tool, minutes per scene), rendered at twice --size and cached in
    /// --reference-cache under a hash of the export and the settings: an unchanged scene
    /// reuses it, a changed one gets a new one.
    #[arg(long)]
    pub make_references: bool,
    /// Samples per pixel of a made reference.
    #[arg(long, default_value_t = 256)]
    pub reference_spp: u32,
    /// Folder of the made references. Default: ~/.cache/voxgi/references.
    #[arg(long)]
    pub reference_cache: Option<PathBuf>,
    /// The Mitsuba reference script (its .venv is the one beside its folder).
    #[arg(long, default_value = "tools/reference")]
    pub reference_tool: PathBuf,
    /// Flicker: positions of the scene's first point, spot or area light along a circle, each
    /// rendered fresh by every configuration and compared with a converged path tracer's
    /// change along the same path (the `flicker` column); 0 leaves the column empty.
    #[arg(long, default_value_t = 4, value_name = "STEPS")]
    pub temporal_steps: u32,
    /// Lag: frames rendered after the scene's first light switches off, at most, until the
    /// image is 95% of the way to the light-off image (the `ghost` and `lag_frames` columns);
    /// 0 leaves them empty.
    #[arg(long, default_value_t = 32, value_name = "FRAMES")]
    pub lag_frames: u32,
    /// Leave out the ray-test comparison (traverse.csv): after the GI rows the sweep casts
    /// `voxgi bench traverse`'s rays on each scene with the hierarchical test, the exact
    /// voxel walk and 1-bit and 3-bit marching at each --traverse-samples, per
    /// --traverse-radii.
    #[arg(long)]
    pub no_traverse: bool,
    /// Ray lengths of the ray-test comparison, in the thesis's test-box units (radius_m =
    /// r / 6 × the scene's largest extent).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_RADII_BOX_UNITS,
          value_name = "R1,R2,…")]
    pub traverse_radii: Vec<f32>,
    /// Marching sample counts of the ray-test comparison (a 1-bit and a 3-bit row each).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_MARCH_STEPS,
          value_name = "N1,N2,…")]
    pub traverse_samples: Vec<u32>,
    /// Side of the CPU-traced G-buffer whose visible surface points the test rays start from.
    #[arg(long, default_value_t = 64, value_name = "PIXELS")]
    pub traverse_gbuffer: u32,
    /// Test rays per surface point (cosine-distributed around its normal).
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub traverse_rays: u32,
    /// Timed runs of every ray test, interleaved, after one untimed warm-up run when more than
    /// 1 (median, fastest and slowest run in the rows).
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub traverse_repeats: u32,
}

/// Arguments of `voxgi tune`.
#[derive(clap::Args, Clone)]
pub struct TuneArgs {
    /// The scene, as `voxgi sweep` named it (a built-in's name or a scene file).
    pub scene: String,
    /// The GPU time allowed to the image, in ms (the path tracer's accumulated frames count).
    #[arg(long, value_name = "MS")]
    pub budget_ms: f64,
    /// The sweep's output folder (its sweep.csv).
    #[arg(long, default_value = "sweep")]
    pub from: PathBuf,
}

/// A scene of the sweep with its reference at the sweep's size, or smaller by
/// `render_factor` (then each render is box-filtered by that factor before scoring).
struct SweepScene {
    name: String,
    scene: Scene,
    reference: HdrImage,
    render_factor: u32,
    /// The renders' width and height: `--size` wide, the reference's aspect.
    render_size: (u32, u32),
}

/// One configuration ready to run: its flags checked and turned into settings.
struct Job {
    config: Config,
    settings: RenderSettings,
}

/// A scene's name: a built-in's name, else the file's stem.
pub fn scene_name(arg: &str) -> String {
    match crate::scene::builtin(arg) {
        Some(_) => arg.to_owned(),
        None => Path::new(arg)
            .file_stem()
            .map_or_else(|| arg.to_owned(), |s| s.to_string_lossy().into_owned()),
    }
}

/// The scenes given, or every built-in and `assets/scenes/*.toml` with a reference.
fn scene_args(args: &SweepArgs) -> Vec<String> {
    if !args.scenes.is_empty() {
        return args.scenes.clone();
    }
    let mut all: Vec<String> = crate::scene::builtin_names()
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    if let Ok(dir) = std::fs::read_dir(crate::assets::find(Path::new("assets/scenes"))) {
        let mut files: Vec<String> = dir
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .map(|p| p.to_string_lossy().into_owned())
            .collect();
        files.sort();
        all.extend(files);
    }
    // One scene per reference: the built-in `cornell` and assets/scenes/cornell.toml are one.
    let mut seen = std::collections::HashSet::new();
    all.retain(|a| {
        let name = scene_name(a);
        reference_path(&args.references, &name).exists() && seen.insert(name)
    });
    all
}

/// `<name>_gi.exr` in `dir`, from the current directory or else the project's root.
fn reference_path(dir: &Path, name: &str) -> PathBuf {
    crate::assets::find(&dir.join(format!("{name}_gi.exr")))
}

/// The reference of a scene named on the command line: `<name>_gi.exr` (voxgi's export
/// rendered by Mitsuba), else the third-party scenes' references of the authors' own scene
/// descriptions, `<name>_authors.exr` or `<name>.exr` (`modern_hall` and `sponza_authors`;
/// docs/measurements/real-scenes.md). The default list takes `<name>_gi.exr` alone, so that a
/// plain `voxgi sweep` keeps its square scenes and its time.
fn named_reference_path(dir: &Path, name: &str) -> PathBuf {
    let gi = reference_path(dir, name);
    if gi.exists() {
        return gi;
    }
    [format!("{name}_authors.exr"), format!("{name}.exr")]
        .iter()
        .map(|f| crate::assets::find(&dir.join(f)))
        .find(|p| p.exists())
        .unwrap_or(gi)
}

/// The renders' size and the reference's box-filter factor (or, when `render_factor` is
/// above 1, the renders') for `--size` (the renders' width) against a `width` × `height`
/// reference: `--size` divides the width (the reference is filtered down), or the width divides `--size` (the
/// renders are), and the height must follow the width's scale exactly. `None`: it does not fit.
fn fit_size(size: u32, width: u32, height: u32) -> Option<((u32, u32), u32, u32)> {
    if size == 0 || width == 0 || height == 0 {
        return None;
    }
    if width.is_multiple_of(size) {
        let f = width / size;
        height
            .is_multiple_of(f)
            .then_some(((size, height / f), f, 1))
    } else if size.is_multiple_of(width) {
        let k = size / width;
        Some(((size, height * k), 1, k))
    } else {
        None
    }
}

/// Loads each scene and its reference, box-filtered to `size`.
fn load_scenes(args: &SweepArgs) -> Result<Vec<SweepScene>, CliError> {
    let list = scene_args(args);
    if list.is_empty() {
        return Err(SweepError::NoScenes {
            dir: args.references.clone(),
        }
        .into());
    }
    // The default list takes every scene it can: one whose files are not there (the
    // generated atrium before `tools/atrium`) is left out with a note.
    let defaults = args.scenes.is_empty();
    let mut loaded = Vec::new();
    for arg in &list {
        match load_scene_arg(Some(arg)) {
            Ok(scene) => loaded.push((scene_name(arg), scene)),
            Err(e) if defaults => eprintln!("skipping {arg}: {e}"),
            Err(e) => return Err(e.into()),
        }
    }
    loaded
        .into_iter()
        .map(|(name, scene)| {
            let mut path = named_reference_path(&args.references, &name);
            if !path.exists() {
                if !args.make_references {
                    return Err(SweepError::NoReference { scene: name, path }.into());
                }
                path = made_reference(args, &name, &scene)?;
            }
            let full = HdrImage::load(&path)?;
            // Either --size divides the reference's width (the reference is box-filtered down
            // to it), or the width divides --size (each render is box-filtered down to the
            // reference before scoring: a 512² sweep against 256² references). The renders
            // keep the reference's aspect (320×180 for the real scenes' references).
            let Some((render_size, reference_factor, render_factor)) =
                fit_size(args.size, full.width, full.height)
            else {
                return Err(SweepError::Size {
                    size: args.size,
                    width: full.width,
                    height: full.height,
                    path,
                }
                .into());
            };
            Ok(SweepScene {
                name,
                scene,
                reference: downsample(&full, reference_factor),
                render_factor,
                render_size,
            })
        })
        .collect()
}

/// The made reference of a scene without one: the cached image when the scene's export and
/// the settings hash to a key already rendered, else a new Mitsuba render (progress on
/// stderr).
fn made_reference(args: &SweepArgs, name: &str, scene: &Scene) -> Result<PathBuf, CliError> {
    use crate::bench::reference_cache as rc;
    let settings = rc::ReferenceSettings {
        size: args.size.saturating_mul(2),
        spp: args.reference_spp.max(1),
        max_depth: crate::export::mitsuba::DEFAULT_MAX_DEPTH,
        seed: 0,
    };
    let cache = args
        .reference_cache
        .clone()
        .unwrap_or_else(rc::default_cache_dir);
    let tool = rc::tool_files(&args.reference_tool).map_err(SweepError::from)?;
    // A fresh export folder: the export leaves unrelated files alone, which would be hashed.
    let export = cache.join("export").join(name);
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| SweepError::Io { path, source }
    };
    if export.exists() {
        std::fs::remove_dir_all(&export).map_err(io(&export))?;
    }
    let report =
        crate::export::mitsuba::export_mitsuba(scene, 0.0, settings.size, settings.size, &export)?;
    for w in &report.warnings {
        eprintln!("warning: {name}: {w}");
    }
    let key = rc::export_key(&export, &settings, &tool).map_err(SweepError::from)?;
    let path = rc::cached_path(&cache, name, &key);
    if path.exists() {
        eprintln!("reference of {name}: reusing {}", path.display());
        return Ok(path);
    }
    rc::mitsuba_python(&args.reference_tool).map_err(SweepError::from)?;
    eprintln!(
        "reference of {name}: rendering with Mitsuba ({}) into {}; this takes minutes",
        settings.text(),
        path.display()
    );
    let start = Instant::now();
    rc::render_reference(&args.reference_tool, name, &export, &settings, &path)
        .map_err(SweepError::from)?;
    std::fs::write(
        path.with_extension("txt"),
        format!(
            "{name}: {} (from {})\n",
            settings.text(),
            report.xml_path.display()
        ),
    )
    .map_err(io(&path))?;
    eprintln!(
        "reference of {name}: done in {}",
        clock(start.elapsed().as_secs_f64())
    );
    Ok(path)
}

/// `voxgi render`'s frame flags alone, to check a configuration's flags as the command
/// line would.
#[derive(clap::Parser)]
#[command(no_binary_name = true)]
struct FrameFlags {
    #[command(flatten)]
    frame: FrameArgs,
}

/// A configuration's render settings on a scene, at `width` × `height`: its flags parsed by
/// clap and checked against their ranges, like `voxgi render`'s.
fn job(config: &Config, scene: &Scene, (width, height): (u32, u32)) -> Result<Job, CliError> {
    use clap::Parser as _;
    let mut argv = vec![
        "--width".to_owned(),
        width.to_string(),
        "--height".to_owned(),
        height.to_string(),
    ];
    argv.extend(config.argv());
    let flag_err = |message: String| SweepError::Flag {
        config: config.label(),
        message,
    };
    let frame = FrameFlags::try_parse_from(&argv)
        .map_err(|e| flag_err(e.kind().to_string() + ": " + e.render().to_string().trim()))?
        .frame;
    let settings = frame.settings(scene).map_err(|e| flag_err(e.to_string()))?;
    Ok(Job {
        config: config.clone(),
        settings,
    })
}

/// The jobs a scene is rendered with: a configuration the renderer refuses (e.g. SAO
/// without GI, screen-space GI through an orthographic camera) is left out with a note on
/// stderr, so that one such job does not end the whole sweep.
fn renderable(scene_name: &str, camera: &crate::scene::Camera, jobs: Vec<Job>) -> Vec<Job> {
    jobs.into_iter()
        .filter(|j| {
            match crate::render::check_setting_combination(&j.settings)
                .and_then(|()| crate::render::check_projection(camera, &j.settings, false))
            {
                Ok(()) => true,
                Err(e) => {
                    eprintln!("skipping {scene_name} {}: {e}", j.config.label());
                    false
                }
            }
        })
        .collect()
}

/// Whether a pass is part of the GI's cost: voxelization, the atlases, the light maps and
/// the `gi_*` passes (the VPL passes are `gi_vpl_*`) and the screen-space GI's `ssgi_*`.
pub fn is_gi_pass(name: &str) -> bool {
    ["gi_", "ssgi_", "light_map", "voxel", "atlas"]
        .iter()
        .any(|p| name.starts_with(p))
}

/// Median, min and max of per-frame sums of the passes `keep` selects.
fn frame_stats(frames: &[Vec<PassTiming>], keep: impl Fn(&str) -> bool) -> [f64; 3] {
    let sums: Vec<f64> = frames
        .iter()
        .map(|f| {
            // + 0.0: an empty float sum is -0.0, which would print as "-0".
            f.iter()
                .filter(|t| keep(&t.name))
                .map(|t| t.gpu_ms)
                .sum::<f64>()
                + 0.0
        })
        .collect();
    [
        median(&sums),
        sums.iter().copied().fold(f64::INFINITY, f64::min),
        sums.iter().copied().fold(0.0, f64::max),
    ]
}

/// Profiles and renders one configuration on one scene and scores it; `path` is the scene's
/// light path with its references, for the flicker column.
fn measure(
    ctx: &Context,
    s: &SweepScene,
    path: Option<&LightPath>,
    job: &Job,
    args: &SweepArgs,
) -> Result<SweepRow, CliError> {
    let run = profile_scene(ctx, &s.scene, &job.settings, args.frames, args.warmup)?;
    let image = render_image(ctx, &s.scene, &job.settings)?;
    let scored = match s.render_factor {
        1 => image.hdr,
        k => downsample(&image.hdr, k),
    };
    let m = crate::eval::compare(&s.reference, &scored, None)?;
    let flicker = path
        .map(|p| path_flicker(ctx, p, &job.settings))
        .transpose()?;
    let lag = lag_after_switch_off(ctx, &s.scene, &job.settings, args.lag_frames)?;
    let gi = frame_stats(&run.frames, is_gi_pass);
    let frame = frame_stats(&run.frames, |_| true);
    let accumulate = crate::render::frames_to_image(&job.settings) as u32;
    Ok(SweepRow {
        scene: s.name.clone(),
        config: job.config.label(),
        method: method_name(job.config.method),
        size: args.size,
        frames: args.frames as u32,
        gi_median_ms: gi[0],
        gi_min_ms: gi[1],
        gi_max_ms: gi[2],
        frame_median_ms: frame[0],
        frame_min_ms: frame[1],
        frame_max_ms: frame[2],
        accumulate_frames: accumulate,
        image_ms: frame[0] * f64::from(accumulate),
        transient_bytes: run.transient_memory.peak_aliased_bytes,
        rel_mse: m.rel_mse,
        flip: m.flip_mean,
        psnr_db: m.psnr_db,
        ssim: m.ssim,
        device: ctx.info.name.clone(),
        gi_toml: settings_inline(&job.settings.gi, &job.config),
        flicker,
        ghost: lag.map(|l| l.ghost),
        lag_frames: lag.and_then(|l| l.frames),
    })
}

/// Writes sweep.json (the GI rows as `rows`, the ray-test rows as `traverse`, and per scene,
/// radius and bit depth the cheapest marching at >= 99% agreement as `traverse_at_99`) and
/// each scene's plot from all rows so far.
fn write_summaries(
    dir: &Path,
    rows: &[SweepRow],
    traverse: &[TraverseRow],
) -> Result<(), CliError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| SweepError::Io { path, source }
    };
    let json = dir.join("sweep.json");
    let doc = serde_json::json!({
        "rows": rows,
        "traverse": traverse,
        "traverse_at_99": march_at_99(traverse),
    });
    std::fs::write(&json, serde_json::to_string_pretty(&doc)?).map_err(io(&json))?;
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.sort_unstable();
    scenes.dedup();
    for scene in scenes {
        let of: Vec<&SweepRow> = rows.iter().filter(|r| r.scene == scene).collect();
        let svg = dir.join(format!("{scene}_pareto.svg"));
        std::fs::write(&svg, pareto_svg(scene, &of)?).map_err(io(&svg))?;
        let png = dir.join(format!("{scene}_pareto.png"));
        pareto_png(scene, &of)?
            .save(&png)
            .map_err(|e| SweepError::Io {
                path: png.clone(),
                source: std::io::Error::other(e),
            })?;
    }
    Ok(())
}

/// The temporal columns of a row for the console, as far as they were measured.
fn temporal_text(row: &SweepRow) -> String {
    let mut t = String::new();
    if let Some(f) = row.flicker {
        t += &format!("  flicker {f:.4}");
    }
    match (row.ghost, row.lag_frames) {
        (Some(g), Some(n)) => t += &format!("  ghost {g:.3}, lag {n} frames"),
        (Some(g), None) => t += &format!("  ghost {g:.3}, lag > --lag-frames"),
        _ => {}
    }
    t
}

/// `m:ss` of a duration in seconds.
fn clock(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

/// Runs the sweep; prints a line per row to `out` and the progress with an ETA to stderr.
pub fn sweep(global: &Global, args: &SweepArgs, out: &mut dyn Write) -> Result<(), CliError> {
    // Every input is checked before the device is up.
    let methods = parse_methods(&args.methods)?;
    let grid = args
        .grid
        .iter()
        .map(|g| parse_grid(g))
        .collect::<Result<Vec<_>, _>>()?;
    let traverse = traverse_desc(args)?;
    let scenes = load_scenes(args)?;
    let configs = configs(&methods, &grid);
    let jobs = scenes
        .iter()
        .map(|s| {
            let jobs = configs
                .iter()
                .map(|c| job(c, &s.scene, s.render_size))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(renderable(&s.name, &s.scene.camera, jobs))
        })
        .collect::<Result<Vec<_>, CliError>>()?;
    std::fs::create_dir_all(&args.out).map_err(|source| SweepError::Io {
        path: args.out.clone(),
        source,
    })?;
    let csv = args.out.join("sweep.csv");
    let mut rows = match (csv.exists(), args.resume) {
        (true, false) => return Err(SweepError::Exists { path: csv }.into()),
        (true, true) => read_csv(&csv)?,
        (false, _) => Vec::new(),
    };
    let traverse_csv = args.out.join("traverse.csv");
    let mut traverse_done: Vec<TraverseRow> = match (traverse_csv.exists(), args.resume) {
        (true, false) if traverse.is_some() => {
            return Err(SweepError::Exists { path: traverse_csv }.into())
        }
        (true, true) => read_rows(&traverse_csv)?,
        _ => Vec::new(),
    };
    if let Some(d) = &traverse {
        let (gbuffer, rays, repeats) = (d.gbuffer_size, d.rays_per_point, d.repeats);
        if let Some(measured) = other_settings(&traverse_done, gbuffer, rays, repeats) {
            return Err(SweepError::TraverseSettings {
                path: traverse_csv,
                measured,
                given: settings_text(gbuffer, rays, repeats),
            }
            .into());
        }
    }
    let traverse_todo = traverse
        .as_ref()
        .map(|desc| traverse_units(&scenes, desc, &traverse_done))
        .unwrap_or_default();
    let done =
        |rows: &[SweepRow], s: &str, c: &str| rows.iter().any(|r| r.scene == s && r.config == c);
    let todo: Vec<(usize, &Job)> = scenes
        .iter()
        .enumerate()
        .flat_map(|(i, _)| jobs[i].iter().map(move |j| (i, j)))
        .filter(|(i, j)| !done(&rows, &scenes[*i].name, &j.config.label()))
        .collect();
    let skipped = jobs.iter().map(Vec::len).sum::<usize>() - todo.len();
    if skipped > 0 {
        eprintln!("resuming: {skipped} row(s) already in {}", csv.display());
    }
    let mut appender = CsvAppender::open(&csv)?;
    let temporal = TemporalDesc {
        steps: args.temporal_steps,
        lag_max_frames: args.lag_frames,
        ..TemporalDesc::default()
    };
    // Each scene's light path and its references, rendered when its first row is due.
    let mut paths: Vec<Option<Option<LightPath>>> = scenes.iter().map(|_| None).collect();
    let start = Instant::now();
    with_context(global, |ctx| -> Result<(), CliError> {
        for (k, (i, job)) in todo.iter().enumerate() {
            let s = &scenes[*i];
            if paths[*i].is_none() {
                paths[*i] = Some(light_path(ctx, &s.scene, &job.settings, &temporal)?);
            }
            let path = paths[*i].as_ref().and_then(Option::as_ref);
            let eta = match k {
                0 => "?".to_owned(),
                _ => clock(start.elapsed().as_secs_f64() / k as f64 * (todo.len() - k) as f64),
            };
            eprintln!(
                "[{}/{}] {} {} (elapsed {}, ETA {eta})",
                k + 1,
                todo.len(),
                s.name,
                job.config.label(),
                clock(start.elapsed().as_secs_f64())
            );
            let row = measure(ctx, s, path, job, args)?;
            appender.append(&row)?;
            outln!(
                out,
                "{:<16} {:<40} {:>9.3} ms  relMSE {:.5}  FLIP {:.4}{}",
                row.scene,
                row.config,
                row.image_ms,
                row.rel_mse,
                row.flip,
                temporal_text(&row)
            );
            rows.push(row);
            write_summaries(&args.out, &rows, &traverse_done)?;
        }
        if todo.is_empty() && traverse_todo.is_empty() {
            write_summaries(&args.out, &rows, &traverse_done)?;
        }
        if let Some(desc) = &traverse {
            let mut file = TraverseOutput {
                csv: &traverse_csv,
                appender: None,
                rows: &mut traverse_done,
                gi_rows: &rows,
                dir: &args.out,
            };
            measure_traverse(ctx, &scenes, desc, &traverse_todo, &mut file, out)?;
        }
        Ok(())
    })?;
    outln!(
        out,
        "wrote {} ({} rows), sweep.json and the plots in {}",
        csv.display(),
        rows.len(),
        args.out.display()
    );
    if traverse.is_some() {
        outln!(
            out,
            "wrote {} ({} rows)",
            traverse_csv.display(),
            traverse_done.len()
        );
    }
    Ok(())
}

/// The ray-test comparison's settings from the flags, checked against their limits (before
/// the device is up); `None` with --no-traverse. Sample counts are sorted (the cheapest
/// marching at 99% is the fewest samples) and repeated values dropped.
fn traverse_desc(args: &SweepArgs) -> Result<Option<TraverseBenchDesc>, CliError> {
    use crate::limits as l;
    if args.no_traverse {
        return Ok(None);
    }
    let mut radii = Vec::new();
    for &r in &args.traverse_radii {
        let r = l::TRAVERSE_RADIUS.check_flag(r)?;
        if !radii.contains(&r) {
            radii.push(r);
        }
    }
    let mut samples = args
        .traverse_samples
        .iter()
        .map(|&s| l::TRAVERSE_SAMPLES.check_flag(s))
        .collect::<Result<Vec<_>, _>>()?;
    samples.sort_unstable();
    samples.dedup();
    Ok(Some(TraverseBenchDesc {
        gbuffer_size: l::TRAVERSE_GBUFFER.check_flag(args.traverse_gbuffer)?,
        rays_per_point: l::TRAVERSE_RAYS.check_flag(args.traverse_rays)?,
        radii_box_units: radii,
        march_steps: samples,
        repeats: l::TRAVERSE_REPEATS.check_flag(args.traverse_repeats)?,
        ..TraverseBenchDesc::default()
    }))
}

/// One radius of one scene still to measure, and the tests it lacks.
struct TraverseUnit {
    scene: usize,
    radius: f32,
    missing: Vec<String>,
}

/// The radii of each scene whose rows `done` lacks some test of `desc`: the whole radius
/// when it has none, else only what it lacks (a resumed sweep with more sample counts).
fn traverse_units(
    scenes: &[SweepScene],
    desc: &TraverseBenchDesc,
    done: &[TraverseRow],
) -> Vec<TraverseUnit> {
    let wanted = traverse_tests(&desc.march_steps);
    let mut units = Vec::new();
    for (i, s) in scenes.iter().enumerate() {
        for &radius in &desc.radii_box_units {
            let missing = missing_tests(done, &s.name, radius, &wanted);
            if !missing.is_empty() {
                units.push(TraverseUnit {
                    scene: i,
                    radius,
                    missing: missing.into_iter().cloned().collect(),
                });
            }
        }
    }
    let skipped = scenes.len() * desc.radii_box_units.len() - units.len();
    if skipped > 0 {
        eprintln!("resuming: {skipped} ray-test radius(es) already in traverse.csv");
    }
    units
}

/// Where the ray-test rows go: traverse.csv (opened at the first row) and, with the GI rows,
/// sweep.json.
struct TraverseOutput<'a> {
    csv: &'a Path,
    appender: Option<CsvAppender<TraverseRow>>,
    rows: &'a mut Vec<TraverseRow>,
    gi_rows: &'a [SweepRow],
    dir: &'a Path,
}

/// Measures each unit (`bench traverse`'s [`bench_radius`]: a scene's voxels and rays are
/// made once, at its first unit), appends its missing rows and prints a line per radius,
/// with the progress and an ETA on stderr.
fn measure_traverse(
    ctx: &Context,
    scenes: &[SweepScene],
    desc: &TraverseBenchDesc,
    units: &[TraverseUnit],
    file: &mut TraverseOutput<'_>,
    out: &mut dyn Write,
) -> Result<(), CliError> {
    let start = Instant::now();
    let mut k = 0;
    for (i, s) in scenes.iter().enumerate() {
        let of: Vec<&TraverseUnit> = units.iter().filter(|u| u.scene == i).collect();
        if of.is_empty() {
            continue;
        }
        eprintln!(
            "{}: voxelizing and tracing a {}² G-buffer for the ray tests",
            s.name, desc.gbuffer_size
        );
        let setup = traverse_rays(
            &s.scene,
            &TraverseBenchDesc {
                radii_box_units: of.iter().map(|u| u.radius).collect(),
                ..desc.clone()
            },
        )?;
        let caster = crate::voxel::gpu_rays::VoxelRayCaster::new(ctx, &setup.hierarchy)?;
        let base = setup.hierarchy.base();
        let context = RadiusContext {
            scene: &s.name,
            grid: [base.res_x(), base.res_y(), base.depth()],
            gbuffer: desc.gbuffer_size,
            points: setup.points,
            repeats: desc.repeats,
            device: &ctx.info.name,
        };
        for (u, (radius, radius_m, rays)) in of.iter().zip(&setup.radii) {
            let eta = match k {
                0 => "?".to_owned(),
                _ => clock(start.elapsed().as_secs_f64() / k as f64 * (units.len() - k) as f64),
            };
            eprintln!(
                "[ray tests {}/{}] {} radius {radius} ({} tests, {} rays; elapsed {}, ETA {eta})",
                k + 1,
                units.len(),
                s.name,
                u.missing.len(),
                rays.len(),
                clock(start.elapsed().as_secs_f64())
            );
            // The hierarchical test and the exact walk always run: every row's agreement
            // and speed-up are against them in the same run.
            let samples: Vec<u32> = desc
                .march_steps
                .iter()
                .copied()
                .filter(|&n| {
                    [1, 3]
                        .iter()
                        .any(|&b| u.missing.contains(&march_test(b, n)))
                })
                .collect();
            let unit_desc = TraverseBenchDesc {
                march_steps: samples,
                ..desc.clone()
            };
            let result = bench_radius(ctx, &caster, &unit_desc, *radius, *radius_m, rays)?;
            let new: Vec<TraverseRow> = traverse_rows(&context, &result)
                .into_iter()
                .filter(|r| u.missing.contains(&r.test))
                .collect();
            if file.appender.is_none() {
                file.appender = Some(CsvAppender::open(file.csv)?);
            }
            if let Some(a) = file.appender.as_mut() {
                for r in &new {
                    a.append(r)?;
                }
            }
            outln!(out, "{}", radius_text(&s.name, &result, &new));
            file.rows.extend(new);
            write_summaries(file.dir, file.gi_rows, file.rows)?;
            k += 1;
        }
    }
    Ok(())
}

/// One radius's measure for the console: the hierarchical test against the exact walk and
/// the cheapest marching at >= 99% agreement.
fn radius_text(scene: &str, r: &crate::bench::RadiusResult, rows: &[TraverseRow]) -> String {
    let mut t = format!(
        "{scene:<16} radius {} ({:.3} m), {} rays, {:.1}% hit:",
        r.radius_box_units,
        r.radius_m,
        r.rays,
        100.0 * r.hit_fraction
    );
    let cpu = |ms: Option<f64>| ms.map_or_else(|| "-".to_owned(), |c| format!("{c:.1}"));
    for m in r.methods.iter().take(2) {
        t += &format!(
            " {} {:.1} GPU / {} CPU ms, {:.1} steps, {:.2}% exact;",
            m.method,
            m.gpu_ms,
            cpu(m.cpu_ms),
            m.mean_steps,
            100.0 * m.exact_agreement
        );
    }
    for a in march_at_99(rows) {
        let bits = a.bits;
        match (a.samples, a.speedup) {
            (Some(n), Some(x)) => {
                let in_cpu = a
                    .cpu_speedup
                    .map_or_else(String::new, |c| format!(", {c:.2}x in CPU ms"));
                t += &format!(
                    " {bits}-bit marching at 99% from {n} samples: hierarchical {x:.2}x \
                     faster{in_cpu};"
                )
            }
            _ if rows
                .iter()
                .any(|r| r.test.starts_with(&format!("march{bits}x"))) =>
            {
                t += &format!(" {bits}-bit marching short of 99%;")
            }
            _ => {}
        }
    }
    t.trim_end_matches(';').to_owned()
}

/// Prints the most accurate configuration of the sweep within the budget as scene tables: its
/// `[gi]` table, and the `[shadow]`, `[post]` and `[voxel]` keys its grid set.
pub fn tune_command(args: &TuneArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let name = scene_name(&args.scene);
    let (row, table, _) = tune_from_dir(&args.from, &name, args.budget_ms)?;
    let row = &row;
    outln!(
        out,
        "# voxgi tune {name} --budget-ms {}: `{}` on {}, {:.3} ms to the image ({} frame(s) of \
         {:.3} ms), relMSE {:.5}, FLIP {:.4}",
        args.budget_ms,
        row.config,
        row.device,
        row.image_ms,
        row.accumulate_frames,
        row.frame_median_ms,
        row.rel_mse,
        row.flip
    );
    outln!(out, "{}", table.trim_end());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_configuration_flag_out_of_range_names_the_configuration() {
        let scene = load_scene_arg(None).expect("cornell");
        let grid = [parse_grid("gi-rays=0").expect("grid")];
        let c = configs(&[crate::gi::GiMethod::Hemisphere], &grid);
        let e = job(&c[0], &scene, (32, 32))
            .err()
            .expect("0 rays")
            .to_string();
        assert!(e.contains("hemisphere gi-rays=0"), "{e}");
        let grid = [parse_grid("vpl-pattern=4y4").expect("grid")];
        let c = configs(&[crate::gi::GiMethod::Vpl], &grid);
        let e = job(&c[0], &scene, (32, 32))
            .err()
            .expect("bad pattern")
            .to_string();
        assert!(e.contains("vpl-pattern") && e.contains("4y4"), "{e}");
        let ok = job(
            &configs(&[crate::gi::GiMethod::Vpl], &[])[0],
            &scene,
            (32, 32),
        )
        .expect("ok");
        assert_eq!(ok.settings.width, 32);
    }

    #[test]
    fn the_renders_keep_the_references_aspect_at_whole_factors() {
        // (render size, the reference's box-filter factor, the renders' factor)
        assert_eq!(fit_size(128, 256, 256), Some(((128, 128), 2, 1)));
        assert_eq!(fit_size(512, 256, 256), Some(((512, 512), 1, 2)));
        // The real scenes' 320×180 references: 64 × 36 (filtered by 5), 640 × 360 (renders
        // filtered by 2); 128 does not divide 320, and 80 gives 180 / 4 = 45 rows.
        assert_eq!(fit_size(64, 320, 180), Some(((64, 36), 5, 1)));
        assert_eq!(fit_size(640, 320, 180), Some(((640, 360), 1, 2)));
        assert_eq!(fit_size(80, 320, 180), Some(((80, 45), 4, 1)));
        assert_eq!(fit_size(128, 320, 180), None);
        // 40 divides 320 (factor 8), but 180 rows do not split into 8.
        assert_eq!(fit_size(40, 320, 180), None);
        assert_eq!(fit_size(0, 256, 256), None);
    }

    #[test]
    fn gi_passes_are_told_from_the_rest() {
        for p in [
            "gi_hemisphere",
            "gi_vpl_generate",
            "light_map",
            "voxelize_triangles",
        ] {
            assert!(is_gi_pass(p), "{p}");
        }
        for p in ["gbuffer", "deferred_direct", "tonemap", "shadow_depth"] {
            assert!(!is_gi_pass(p), "{p}");
        }
    }
}

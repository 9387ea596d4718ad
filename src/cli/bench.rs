//! `voxgi bench traverse|voxelize|voxelize-sweep|dynamic|flicker|camera-path|soak|leak|ssgi|ssgi-limits`: the benchmarks of [`crate::bench`].

use super::{out, outln, with_context, CliError, Global};
use crate::bench::{
    bench_dynamic, bench_flicker, bench_leak, bench_soak, bench_traverse, bench_voxelize_atlas,
    bench_voxelize_sweep, DynamicBenchDesc, FlickerBenchDesc, LeakBenchDesc, SoakBenchDesc,
    TraverseBenchDesc, VoxelizeBenchDesc, VoxelizeSweepDesc,
};
use crate::gi::GiMethod;
use crate::scene::{load_scene_arg, DEFAULT_SCENE};
use crate::voxel::TraversalParams;
use serde::Serialize;
use std::io::Write;

/// The benchmarks.
#[derive(clap::Subcommand, Clone)]
pub enum BenchCommand {
    /// Voxelization GPU time, atlas and triangle voxelizer side by side: Cornell, bunny-in-box
    /// and a dense generated scene (64 bunnies) at each x,y resolution (D = 128), and a cube
    /// tessellated 1x and 16x (same surface). One-time atlas work is listed apart.
    VoxelizeSweep {
        /// x = y resolutions of the scene rows.
        #[arg(long, value_delimiter = ',', default_values_t = [64, 128, 256, 512])]
        resolutions: Vec<u32>,
        /// Timed runs per measurement (the median is printed).
        #[arg(long, default_value_t = 5)]
        reps: usize,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Hierarchical voxel ray test vs uniform 1-bit marching on the same rays (Thiedemann 2010, §9.3.1):
    /// GPU ms, rays/s, steps per ray, and the marching samples needed to match >= 99% of
    /// the hierarchical results.
    Traverse(TraverseArgs),
    /// Temporal stability: the first point or spot light moves along a circle; every method
    /// renders each step and its frame-to-frame change is compared with a converged path
    /// tracer's along the same path (flicker = the change the reference does not have).
    Flicker {
        /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
        scene: Option<String>,
        /// Light positions along the path.
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=1024))]
        steps: u32,
        /// Image width and height in pixels.
        #[arg(long, default_value_t = 96, value_parser = clap::value_parser!(u32).range(8..=4096))]
        size: u32,
        /// Frames the reference path tracer accumulates per step.
        #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
        reference_frames: u32,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Temporal accumulation along a camera path: the camera flies the scene's
    /// `[camera_path]` while its animation plays, one frame per step; each method renders the
    /// flight with and without temporal accumulation (same rays per frame), and a few frames
    /// along it are scored against Mitsuba 3's images of those frames (relMSE, FLIP; made once
    /// and cached), with the flicker there and the ghost and lag after a light switch.
    CameraPath(CameraPathArgs),
    /// Animated objects voxelized again every frame over a static scene voxelized once
    /// (Thiedemann 2010 §8.2, Figs. 41/42): Cornell walls with 16 static bunnies and N
    /// flying ones; per voxelizer, the bits alone (hemisphere) and with the attribute volumes
    /// (path tracer): GPU ms per frame of the bit passes, the attribute passes and the frame.
    Dynamic {
        /// Numbers of animated bunnies.
        #[arg(long, value_delimiter = ',', default_values_t = [0, 3, 9],
              value_parser = clap::value_parser!(u32).range(0..=256))]
        animated: Vec<u32>,
        /// Image width and height in pixels.
        #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=4096))]
        size: u32,
        /// Measured frames (the scene's time advances 50 ms per frame).
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=10000))]
        frames: u32,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Light leaking: two closed rooms split by one solid wall of 0.25-4 GI voxels, a spot
    /// light in room A only. Per method and wall: the leaked fraction = mean indirect radiance
    /// of room B's image / that of the mirrored view in room A (truth: 0).
    Leak {
        /// Methods: hemisphere, hemisphere-volume (radiance volume), pathtrace, vpl, ssgi.
        #[arg(long, value_delimiter = ',',
              value_parser = ["hemisphere", "hemisphere-volume", "pathtrace", "vpl", "ssgi"],
              default_values = ["hemisphere", "hemisphere-volume", "pathtrace", "vpl", "ssgi"])]
        methods: Vec<String>,
        /// Where room A's spot shines: wall (a disk on the dividing wall), floor (room A's
        /// floor, from beside the wall, pointing away from it).
        #[arg(long, value_delimiter = ',', default_values = ["wall", "floor"])]
        lights: Vec<crate::bench::LeakLight>,
        /// Wall thicknesses in voxels of the GI grid, in (0, 16].
        #[arg(long, value_delimiter = ',', default_values_t = crate::bench::DEFAULT_WALLS_VOXELS)]
        walls: Vec<f32>,
        /// Image width and height in pixels.
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=4096))]
        size: u32,
        /// Print CSV instead of the table.
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Screen-space GI scalability (Oetke 2017 Fig. 4.8): every mip filter × GI resolution ×
    /// samples per texel and level, with the GPU ms of each ssgi stage and of the frame
    /// (median [min, max]) and the image's relMSE and FLIP against the scene's reference.
    Ssgi(SsgiArgs),
    /// The screen-space method's limitations (Oetke 2017 §7) on purpose-made scenes: light
    /// from off-screen (the camera turns away from a lit wall) and missing indirect shadows
    /// (a panel seen edge-on): the indirect light in view of `ssgi` and of the voxel path
    /// tracer as a fraction of Mitsuba's (references made once and cached; leaking through
    /// thin walls: `voxgi bench leak`).
    SsgiLimits {
        /// Image width and height in pixels (references at the same size).
        #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=1024))]
        size: u32,
        /// Frames each method accumulates (ssgi: feedback bounces and history).
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
        frames: u32,
        #[command(flatten)]
        references: ReferenceArgs,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Long runs: each method renders many frames of a scene with moving objects; every
    /// `--every` frames the process RSS, the GPU memory the context holds and the release
    /// queue's backlog are printed, and at the end their growth in bytes per 1000 frames
    /// (least squares over the samples after the first). Flat means no leak.
    Soak(SoakArgs),
    /// Atlas binary voxelization two ways on the same points: the compute pass (atomicOr into
    /// the column buffer) vs the thesis's raster pass (single-bit LUT, logicOp OR): GPU ms and
    /// whether the bits agree.
    Voxelize {
        /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
        scene: Option<String>,
        /// Voxel grid x/y resolution cap.
        #[arg(long, default_value_t = 128)]
        resolution: u32,
        /// Depth layers of 128 voxels.
        #[arg(long, default_value_t = 1)]
        layers: u32,
        /// Runs of each pass (the median is reported).
        #[arg(long, default_value_t = 10)]
        repeats: u32,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
}

/// The arguments of `voxgi bench traverse`.
#[derive(clap::Args, Clone)]
pub struct TraverseArgs {
    /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
    scene: Option<String>,
    /// Voxel grid x/y resolution (depth 128).
    #[arg(long, default_value_t = 128)]
    resolution: u32,
    /// G-buffer size in pixels per side (surface points rays start from).
    #[arg(long, default_value_t = 128)]
    gbuffer: u32,
    /// Rays per surface point.
    #[arg(long, default_value_t = 16)]
    rays: u32,
    /// Hierarchy levels the traversal starts at (thesis §5.3.2); the first is the
    /// reference of the agreement columns, each further one a row of its own.
    #[arg(long, value_delimiter = ',', default_values_t = [1],
          value_parser = clap::value_parser!(u32).range(0..=14))]
    start_level: Vec<u32>,
    /// Iteration cap of the hierarchical traversal.
    #[arg(long, default_value_t = 1024)]
    max_iterations: u32,
    /// Ray lengths in units of the thesis's test box (radius_m = r / 6 × the scene's
    /// largest extent).
    #[arg(long, value_delimiter = ',', default_values_t = [2.0, 4.0, 8.0])]
    radii: Vec<f32>,
    /// Marching sample counts (1-bit and 3-bit rows each).
    #[arg(long, value_delimiter = ',', default_values_t = [8, 16, 32, 64, 128, 256, 512],
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    march_steps: Vec<u32>,
    /// Leave out the marching rows (only the hierarchical test and the exact walk).
    #[arg(long)]
    no_march: bool,
    /// Timed runs of every method, interleaved, after one untimed warm-up run: the
    /// median and the fastest and slowest run are printed.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeats: u32,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

impl TraverseArgs {
    fn run(&self, global: &Global, out: &mut dyn Write) -> Result<(), CliError> {
        let Self {
            scene,
            resolution,
            gbuffer,
            rays,
            start_level,
            max_iterations,
            radii,
            march_steps,
            no_march,
            repeats,
            json,
        } = self;
        let scene = load_scene_arg(scene.as_deref())?;
        with_context(global, |ctx| {
            let desc = TraverseBenchDesc {
                resolution: *resolution,
                gbuffer_size: *gbuffer,
                rays_per_point: *rays,
                radii_box_units: radii.clone(),
                march_steps: if *no_march {
                    Vec::new()
                } else {
                    march_steps.clone()
                },
                params: start_level
                    .iter()
                    .map(|&start_level| TraversalParams {
                        start_level,
                        max_iterations: *max_iterations,
                    })
                    .collect(),
                repeats: *repeats,
                ..Default::default()
            };
            let report = bench_traverse(ctx, &scene, &desc)?;
            print(out, *json, &report, || report.table())?;
            Ok(())
        })
    }
}

/// The arguments of `voxgi bench soak`.
#[derive(clap::Args, Clone)]
pub struct SoakArgs {
    /// A built-in scene or a TOML scene file; objects with keyframes move. Default:
    /// `assets/scenes/cornell_mover.toml` (embedded: runs from any directory).
    scene: Option<String>,
    /// Frames per method.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    frames: u64,
    /// Frames between samples.
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    every: u64,
    /// Image width in pixels.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(8..=4096))]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(8..=4096))]
    height: u32,
    /// The GI methods, run one after another.
    #[arg(long, value_delimiter = ',', default_values = ["none", "hemisphere", "pathtrace", "vpl", "ssgi"])]
    methods: Vec<GiMethod>,
    /// Print JSON instead of the progress lines and the table.
    #[arg(long)]
    json: bool,
}

impl SoakArgs {
    fn run(&self, global: &Global, out: &mut dyn Write) -> Result<(), CliError> {
        let Self {
            scene,
            frames,
            every,
            width,
            height,
            methods,
            json,
        } = self;
        let (name, loaded) = match scene {
            Some(arg) => (arg.clone(), load_scene_arg(Some(arg))?),
            None => (SOAK_SCENE_NAME.to_owned(), soak_default_scene()?),
        };
        with_context(global, |ctx| {
            let desc = SoakBenchDesc {
                frames: *frames as usize,
                every: *every as usize,
                width: *width,
                height: *height,
                methods: methods.clone(),
                ..Default::default()
            };
            let mut progress = |method: GiMethod, s: &crate::bench::SoakSample| {
                if !*json {
                    let rss = s
                        .rss_bytes
                        .map_or("unavailable".to_owned(), |b| b.to_string());
                    let _ = writeln!(
                        out,
                        "{:<11} frame {:>8}  RSS {:>12} B  GPU {:>12} B  pending {}",
                        format!("{method:?}").to_lowercase(),
                        s.frame,
                        rss,
                        s.gpu_bytes,
                        s.pending_releases
                    );
                    let _ = out.flush();
                }
            };
            let report = bench_soak(ctx, &loaded, &name, &desc, &mut progress)?;
            print(out, *json, &report, || report.table())?;
            Ok(())
        })
    }
}

/// The arguments of `voxgi bench ssgi`.
#[derive(clap::Args, Clone)]
pub struct SsgiArgs {
    /// A built-in scene or a TOML scene file with a reference `<name>_gi.exr` in
    /// --references. Default: cornell.
    scene: Option<String>,
    /// Depth/normal mip filters.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["fast", "voting"])]
    mips: Vec<crate::gi::SsgiMips>,
    /// GI resolutions.
    #[arg(long, value_enum, value_delimiter = ',',
          default_values = ["full", "half", "quarter", "eighth"])]
    resolutions: Vec<crate::gi::SsgiResolution>,
    /// Samples per texel and pyramid level.
    #[arg(long, value_delimiter = ',', default_values_t = [16, 32, 64, 128, 256])]
    samples: Vec<u32>,
    /// Image width and height in pixels; must divide the reference's size.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=4096))]
    size: u32,
    /// Frames profiled per configuration (after --warmup).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    frames: u64,
    /// Frames run before profiling.
    #[arg(long, default_value_t = 3)]
    warmup: usize,
    /// Frames of the scored image (feedback bounces and the temporal blend).
    #[arg(long, default_value_t = 8)]
    gi_frames: u32,
    /// Folder of the reference images.
    #[arg(long, default_value = "assets/references")]
    references: std::path::PathBuf,
    /// Print CSV instead of the table.
    #[arg(long, conflicts_with = "json")]
    csv: bool,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
}

impl SsgiArgs {
    fn run(&self, global: &Global, out: &mut dyn Write) -> Result<(), CliError> {
        let Self {
            scene,
            mips,
            resolutions,
            samples,
            size,
            frames,
            warmup,
            gi_frames,
            references,
            csv,
            json,
        } = self;
        for &n in samples {
            crate::scene::gi_range::SSGI_SAMPLES.check_as("--samples", i64::from(n))?;
        }
        crate::scene::gi_range::GI_FRAMES.check_flag(*gi_frames)?;
        let arg = scene.as_deref().unwrap_or(DEFAULT_SCENE);
        let name = super::sweep::scene_name(arg);
        let loaded = load_scene_arg(Some(arg))?;
        let reference = crate::bench::load_reference(references, &name, *size)?;
        with_context(global, |ctx| {
            let desc = crate::bench::SsgiBenchDesc {
                mips: mips.clone(),
                resolutions: resolutions.clone(),
                samples: samples.clone(),
                size: *size,
                frames: *frames as usize,
                warmup: *warmup,
                gi_frames: *gi_frames,
            };
            let report = crate::bench::bench_ssgi(ctx, &loaded, &name, &reference, &desc)?;
            if *csv {
                out!(out, "{}", report.csv());
            } else {
                print(out, *json, &report, || report.table())?;
            }
            Ok(())
        })
    }
}

/// Runs one benchmark and prints its report (a table, or JSON with `--json`).
pub fn bench(global: &Global, command: &BenchCommand, out: &mut dyn Write) -> Result<(), CliError> {
    match command {
        BenchCommand::Traverse(args) => args.run(global, out),
        BenchCommand::Voxelize {
            scene,
            resolution,
            layers,
            repeats,
            json,
        } => {
            let scene = load_scene_arg(scene.as_deref())?;
            with_context(global, |ctx| {
                let desc = VoxelizeBenchDesc {
                    resolution: *resolution,
                    layers: *layers,
                    repeats: *repeats,
                };
                let report = bench_voxelize_atlas(ctx, &scene, &desc)?;
                print(out, *json, &report, || report.table())?;
                Ok(())
            })
        }
        BenchCommand::Flicker {
            scene,
            steps,
            size,
            reference_frames,
            json,
        } => {
            let name = scene.clone().unwrap_or_else(|| DEFAULT_SCENE.to_owned());
            let scene = load_scene_arg(scene.as_deref())?;
            with_context(global, |ctx| {
                let desc = FlickerBenchDesc {
                    steps: *steps,
                    size: *size,
                    reference_frames: *reference_frames,
                    ..Default::default()
                };
                let report = bench_flicker(ctx, &scene, &name, &desc)?;
                print(out, *json, &report, || report.table())?;
                Ok(())
            })
        }
        BenchCommand::CameraPath(args) => args.run(global, out),
        BenchCommand::Soak(args) => args.run(global, out),
        BenchCommand::Dynamic {
            animated,
            size,
            frames,
            json,
        } => with_context(global, |ctx| {
            let desc = DynamicBenchDesc {
                animated: animated.clone(),
                size: *size,
                frames: *frames as usize,
                ..Default::default()
            };
            let report = bench_dynamic(ctx, &desc)?;
            print(out, *json, &report, || report.table())
        }),
        BenchCommand::Leak {
            methods,
            lights,
            walls,
            size,
            csv,
            json,
        } => {
            // clap admits only the names `leak_methods` lists.
            let chosen = crate::bench::leak_methods()
                .into_iter()
                .filter(|(name, _)| methods.contains(name))
                .collect();
            with_context(global, |ctx| {
                let desc = LeakBenchDesc {
                    walls_voxels: walls.clone(),
                    lights: lights.clone(),
                    size: *size,
                    methods: chosen,
                    ..Default::default()
                };
                let report = bench_leak(ctx, &desc)?;
                if *csv {
                    out!(out, "{}", report.csv());
                } else {
                    print(out, *json, &report, || report.table())?;
                }
                Ok(())
            })
        }
        BenchCommand::Ssgi(args) => args.run(global, out),
        BenchCommand::SsgiLimits {
            size,
            frames,
            references,
            json,
        } => with_context(global, |ctx| {
            let refs = references.references();
            let report = ssgi_limits(ctx, *size, *frames, &refs)?;
            print(out, *json, &report, || report.table())?;
            Ok(())
        }),
        BenchCommand::VoxelizeSweep {
            resolutions,
            reps,
            json,
        } => with_context(global, |ctx| {
            let desc = VoxelizeSweepDesc {
                resolutions: resolutions.clone(),
                reps: *reps,
                ..Default::default()
            };
            let report = bench_voxelize_sweep(ctx, &desc)?;
            print(out, *json, &report, || report.table())?;
            Ok(())
        }),
    }
}

/// The soak benchmark's default scene: Cornell walls and a keyframed cube that moves.
const SOAK_SCENE_NAME: &str = "assets/scenes/cornell_mover.toml";
const SOAK_SCENE_TOML: &str = include_str!("../../assets/scenes/cornell_mover.toml");

/// [`SOAK_SCENE_TOML`], parsed like a scene file (it names only built-in meshes, so the base
/// directory is unused).
fn soak_default_scene() -> Result<crate::scene::Scene, crate::scene::SceneError> {
    let origin = std::path::Path::new(SOAK_SCENE_NAME);
    crate::scene::Scene::from_toml_str(SOAK_SCENE_TOML, origin, std::path::Path::new("."))
}

/// A report as pretty JSON or as its table.
fn print(
    out: &mut dyn Write,
    json: bool,
    report: &impl Serialize,
    table: impl FnOnce() -> String,
) -> Result<(), CliError> {
    if json {
        outln!(out, "{}", serde_json::to_string_pretty(report)?);
    } else {
        out!(out, "{}", table());
    }
    Ok(())
}

/// The Mitsuba-reference flags of `bench ssgi-limits` and `bench camera-path`.
#[derive(clap::Args, Clone)]
pub struct ReferenceArgs {
    /// Samples per pixel of the Mitsuba references.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    reference_spp: u32,
    /// Render missing references with Mitsuba 3 (`tools/reference`; minutes each).
    #[arg(long)]
    make_references: bool,
    /// The reference cache [default: ~/.cache/voxgi/references].
    #[arg(long, value_name = "DIR")]
    reference_cache: Option<std::path::PathBuf>,
    /// The reference script.
    #[arg(long, value_name = "PATH", default_value = "tools/reference")]
    reference_tool: std::path::PathBuf,
}

impl ReferenceArgs {
    fn references(&self) -> References {
        References {
            spp: self.reference_spp,
            make: self.make_references,
            cache: self
                .reference_cache
                .clone()
                .unwrap_or_else(crate::bench::reference_cache::default_cache_dir),
            tool: self.reference_tool.clone(),
        }
    }
}

/// Where `voxgi bench ssgi-limits` and `bench camera-path` find or make their Mitsuba
/// references.
struct References {
    spp: u32,
    make: bool,
    cache: std::path::PathBuf,
    tool: std::path::PathBuf,
}

/// The Mitsuba image of `scene` at `size`² with `max_depth` (64 full GI, 2 direct light):
/// the cached one when the export hashes to a key already rendered, else a new render when
/// `refs.make`, else an error naming `--make-references`.
fn limit_reference(
    refs: &References,
    bench: &'static str,
    name: &str,
    (scene, time_s): (&crate::scene::Scene, f32),
    size: u32,
    max_depth: u32,
) -> Result<crate::eval::HdrImage, CliError> {
    use crate::bench::reference_cache as rc;
    use crate::bench::sweep::SweepError;
    let settings = rc::ReferenceSettings {
        size,
        spp: refs.spp,
        max_depth,
        seed: 0,
    };
    let tool = rc::tool_files(&refs.tool).map_err(SweepError::from)?;
    let export = refs.cache.join("export").join(name);
    let io = |path: &std::path::Path| {
        let path = path.to_owned();
        move |source| SweepError::Io { path, source }
    };
    if export.exists() {
        std::fs::remove_dir_all(&export).map_err(io(&export))?;
    }
    crate::export::mitsuba::export_mitsuba(scene, time_s, size, size, &export)?;
    let key = rc::export_key(&export, &settings, &tool).map_err(SweepError::from)?;
    let path = rc::cached_path(&refs.cache, name, &key);
    if !path.exists() {
        if !refs.make {
            return Err(crate::bench::BenchError::NoLimitReference {
                bench,
                scene: name.to_owned(),
                path,
            }
            .into());
        }
        rc::mitsuba_python(&refs.tool).map_err(SweepError::from)?;
        eprintln!(
            "reference of {name}: rendering with Mitsuba ({})",
            settings.text()
        );
        rc::render_reference(&refs.tool, name, &export, &settings, &path)
            .map_err(SweepError::from)?;
    }
    Ok(crate::eval::HdrImage::load(&path)?)
}

/// Runs the cases of [`crate::bench::ssgi_limits`]: per view the direct-only image, `ssgi`
/// and the voxel path tracer after `frames` frames, and Mitsuba's full-GI and direct images.
fn ssgi_limits(
    ctx: &crate::vk::Context,
    size: u32,
    frames: u32,
    refs: &References,
) -> Result<crate::bench::ssgi_limits::LimitReport, CliError> {
    use crate::bench::ssgi_limits as sl;
    let methods = [GiMethod::Ssgi, GiMethod::Pathtrace];
    let mut rows = Vec::new();
    for case in sl::limit_cases(size)? {
        for (k, (view, scene)) in case.views.iter().enumerate() {
            let name = format!("ssgi-limits-{}-{k}", case.case);
            let gi = limit_reference(refs, "ssgi-limits", &name, (scene, 0.0), size, 64)?;
            let direct = limit_reference(
                refs,
                "ssgi-limits",
                &format!("{name}-direct"),
                (scene, 0.0),
                size,
                2,
            )?;
            let mask = case.mask.as_deref();
            let reference = sl::indirect_mean(&gi, &direct, mask);
            let own_direct = sl::render(ctx, scene, size, sl::method_settings(GiMethod::None, 1))?;
            let mut measured = Vec::new();
            for method in methods {
                let img = sl::render(ctx, scene, size, sl::method_settings(method, frames))?;
                let v = sl::indirect_mean(&img, &own_direct, mask);
                measured.push((method.name().to_owned(), v, v / reference));
            }
            eprintln!("{} {view}: done", case.case);
            rows.push(sl::LimitRow {
                case: case.case.into(),
                view: view.clone(),
                reference,
                methods: measured,
            });
        }
    }
    Ok(sl::LimitReport {
        size,
        frames,
        reference_spp: refs.spp,
        rows,
    })
}

/// `voxgi bench camera-path`'s arguments.
#[derive(clap::Args, Clone)]
pub struct CameraPathArgs {
    /// A scene file with a `[camera_path]` table. Default: assets/scenes/cornell_mover.toml.
    scene: Option<String>,
    /// Image width and height in pixels (references at the same size).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=1024))]
    size: u32,
    /// Frames along the path.
    #[arg(long, default_value_t = 48, value_parser = clap::value_parser!(u32).range(2..=4096))]
    frames: u32,
    /// Frames scored against Mitsuba, evenly spaced, the last included.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    scored: u32,
    /// Rays per pixel and frame.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=256))]
    rays: u32,
    /// Methods, each with and without temporal accumulation.
    #[arg(long, value_delimiter = ',', default_values = ["hemisphere", "vpl", "pathtrace"],
          value_parser = ["hemisphere", "vpl", "pathtrace"])]
    methods: Vec<String>,
    /// The spatial filter [default: the methods' own, geometric].
    #[arg(long, value_enum)]
    gi_filter: Option<crate::gi::GiFilterKind>,
    /// The filter's passes (geometric: h+v pairs; svgf: à-trous iterations) [default: the
    /// methods' own].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16), requires = "gi_filter")]
    gi_filter_passes: Option<u32>,
    /// Frames each method's converged images (the noise and flicker measures) accumulate,
    /// with the camera still.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
    converged_frames: u32,
    /// Rays per pixel and frame of those converged images.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=256))]
    converged_rays: u32,
    #[command(flatten)]
    references: ReferenceArgs,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
}

/// The camera-path benchmark's default scene: the Cornell walls with a moving cube, and a
/// flight round it.
const CAMERA_PATH_SCENE: &str = "assets/scenes/cornell_mover.toml";

impl CameraPathArgs {
    fn run(&self, global: &Global, out: &mut dyn Write) -> Result<(), CliError> {
        use crate::bench::camera_path as cp;
        let (name, scene) = match &self.scene {
            Some(s) => (s.clone(), load_scene_arg(Some(s))?),
            None => (CAMERA_PATH_SCENE.to_owned(), soak_default_scene()?),
        };
        let path = scene
            .camera_path
            .clone()
            .ok_or_else(|| CliError::NoCameraPath {
                command: "voxgi bench camera-path",
                scene: name.clone(),
            })?;
        let refs = self.references.references();
        let desc = cp::CameraPathDesc {
            size: self.size,
            frames: self.frames,
            scored: self.scored,
            rays: self.rays,
            filter: self.gi_filter.map(|f| {
                let passes = crate::gi::GiSettings::default().filter_passes;
                (f, self.gi_filter_passes.unwrap_or(passes))
            }),
            converged_frames: self.converged_frames,
            converged_rays: self.converged_rays,
            methods: self
                .methods
                .iter()
                .filter_map(|m| GiMethod::ALL.iter().copied().find(|g| g.name() == m))
                .collect(),
            ..Default::default()
        };
        // The references first: without Mitsuba nothing is rendered for nothing.
        let times = cp::flight_times(&path, desc.frames);
        let stem = std::path::Path::new(&name)
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
        let mut references = Vec::new();
        for k in cp::scored_frames(desc.frames, desc.scored) {
            let at = cp::scene_at(&scene, &path, times[k]);
            let key = format!("camera-path-{stem}-{}-{k}", desc.frames);
            references.push(limit_reference(
                &refs,
                "camera-path",
                &key,
                (&at, times[k]),
                desc.size,
                64,
            )?);
        }
        let reference_name = format!("Mitsuba 3, {} spp", refs.spp);
        with_context(global, |ctx| {
            let report = cp::bench_camera_path(
                ctx,
                &scene,
                &name,
                &path,
                &desc,
                &references,
                &reference_name,
            )?;
            print(out, self.json, &report, || report.table())
        })
    }
}

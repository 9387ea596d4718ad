//! The `voxgi` command line. Everything but argument handling lives in the library.

use anyhow::{bail, Context as _, Result};
use clap::{Parser, Subcommand};
use std::io::Write as _;
use std::path::PathBuf;
use voxgi::demo::Demo;
use voxgi::gi::GiMethod;
use voxgi::light::PointShadow;
use voxgi::post::ToneOperator;
use voxgi::profile::ProfileReport;
use voxgi::render::{profile_scene, render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, resolve_gi, GiOverrides, Scene};
use voxgi::vk::{Context, ContextDesc, FrameLoop, MAX_FRAMES_IN_FLIGHT};

#[derive(Parser)]
#[command(
    name = "voxgi",
    version,
    about = "Vulkan voxel global illumination: render, profile and measure"
)]
struct Cli {
    /// Enable the Khronos validation layer with synchronization validation; any message
    /// makes the command fail.
    #[arg(long, global = true)]
    validate: bool,
    /// Vulkan device: index or part of its name (default: discrete > integrated > CPU;
    /// also VOXGI_DEVICE).
    #[arg(long, global = true)]
    device: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Renders a scene headless to PNG (tone-mapped) and optionally EXR (linear radiance).
    Render {
        /// A built-in scene (cornell, cornell-point) or a TOML scene file. Default: cornell.
        scene: Option<String>,
        /// Output PNG (tone-mapped, sRGB).
        #[arg(short, long, default_value = "voxgi.png")]
        output: PathBuf,
        /// Also write the linear HDR radiance (W/(m² sr)) as OpenEXR.
        #[arg(long)]
        exr: Option<PathBuf>,
        #[command(flatten)]
        frame: FrameArgs,
        /// Compare the linear radiance with a reference EXR and print the metrics.
        #[arg(long)]
        compare: Option<PathBuf>,
    },
    /// Runs the frame N times after warm-up and prints per-pass GPU milliseconds
    /// (median, min, max).
    Profile {
        /// A built-in scene or a TOML scene file. Default: cornell.
        scene: Option<String>,
        /// Profile the render-graph demo frame instead of a scene.
        #[arg(long)]
        demo: bool,
        #[command(flatten)]
        frame: FrameArgs,
        /// Frames measured after warm-up.
        #[arg(long, default_value_t = 100)]
        frames: usize,
        /// Frames run before measuring.
        #[arg(long, default_value_t = 10)]
        warmup: usize,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Prints the compiled render graph: passes, barriers, lifetimes, transient memory.
    Graph {
        /// A built-in scene or a TOML scene file. Default: cornell.
        scene: Option<String>,
        /// The render-graph demo frame instead of a scene's frame.
        #[arg(long)]
        demo: bool,
        /// Graphviz dot instead of text.
        #[arg(long)]
        dot: bool,
        #[command(flatten)]
        frame: FrameArgs,
    },
    /// Opens the interactive viewer: fly camera (WASD, Q/E, right mouse), a panel with per-pass
    /// GPU times, light, tone-mapping, shadow and global-illumination controls; F12 writes a
    /// screenshot.
    View {
        /// A built-in scene or a TOML scene file. Default: cornell.
        scene: Option<String>,
        /// Initial window width and height, pixels.
        #[arg(long, default_value_t = 1280)]
        width: u32,
        #[arg(long, default_value_t = 720)]
        height: u32,
        #[arg(long, value_enum, default_value_t = ToneOperator::Filmic)]
        tonemap: ToneOperator,
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
        /// Start with a voxel debug view instead of the lit image (the panel switches views).
        #[arg(long, value_enum)]
        debug: Option<voxgi::voxel::debug_view::DebugView>,
        /// The object whose atlas the atlas view shows: its name or index in the scene.
        #[arg(long, default_value = "0")]
        object: String,
        /// Scripted run (tests): exit after N presented frames, writing --screenshot.
        #[arg(long)]
        frames: Option<u64>,
        /// Scripted run: resize the window to WxH halfway through.
        #[arg(long, value_parser = parse_size)]
        resize: Option<(u32, u32)>,
        /// Scripted run: minimize the window after FRAME presented frames, restore it after
        /// --restore-after skipped redraws (needs a window manager; under Xvfb e.g. openbox).
        #[arg(long, value_name = "FRAME")]
        minimize_at: Option<u64>,
        /// Scripted run: redraws to skip while minimized before restoring the window.
        #[arg(long, value_name = "N", default_value_t = 10)]
        restore_after: u64,
        /// Screenshot PNG path (F12 / the panel button; the end of a scripted run).
        #[arg(long)]
        screenshot: Option<PathBuf>,
        // The initial indirect light; the panel changes it.
        #[command(flatten)]
        gi: GiArgs,
    },
    /// Lists Vulkan devices and whether voxgi can use them.
    Devices,
    /// Benchmarks measured side by side in one GPU run.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Writes a Mitsuba 3 scene (XML + PLY meshes) identical to a voxgi scene, for reference
    /// rendering with tools/reference.
    ExportMitsuba {
        /// A built-in scene or a TOML scene file. Default: cornell.
        scene: Option<String>,
        /// Output directory.
        #[arg(short, long)]
        output: PathBuf,
        #[arg(long, default_value_t = 256)]
        width: u32,
        #[arg(long, default_value_t = 256)]
        height: u32,
        /// Scene time in seconds (animations).
        #[arg(long, default_value_t = 0.0)]
        time: f32,
    },
    /// Compares two images (EXR or PNG): relMSE, PSNR, SSIM, FLIP, mean/max absolute error.
    Compare {
        /// The reference image.
        reference: PathBuf,
        /// The image under test.
        test: PathBuf,
        /// Writes a FLIP error heatmap (PNG).
        #[arg(long)]
        heatmap: Option<PathBuf>,
        /// An image of the same size whose bright pixels (luminance > 0.5) are excluded from
        /// every metric, e.g. the sky.
        #[arg(long)]
        mask: Option<PathBuf>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
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
    /// Hierarchical voxel ray test vs uniform 1-bit marching on the same rays (thesis §9.3.1):
    /// GPU ms, rays/s, steps per ray, and the marching samples needed to match >= 99% of
    /// the hierarchical results.
    Traverse {
        /// A built-in scene or a TOML scene file. Default: cornell.
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
        /// Hierarchy level the traversal starts at (thesis §4.5).
        #[arg(long, default_value_t = 1)]
        start_level: u32,
        /// Iteration cap of the hierarchical traversal.
        #[arg(long, default_value_t = 1024)]
        max_iterations: u32,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
    },
    /// Atlas binary voxelization two ways on the same points: the compute pass (atomicOr into
    /// the column buffer) vs the thesis's raster pass (single-bit LUT, logicOp OR): GPU ms and
    /// whether the bits agree.
    Voxelize {
        /// A built-in scene or a TOML scene file. Default: cornell.
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

/// Indirect-light flags of `render`, `profile`, `graph` and `view`. Each one given overrides the
/// scene file's `[gi]` value, which overrides the default shown.
#[derive(clap::Args, Clone, Debug, Default)]
struct GiArgs {
    /// Indirect-light method (none: direct light only) [default: the scene's `[gi] method`,
    /// else none].
    #[arg(long, value_enum)]
    gi: Option<GiMethod>,
    /// Where hemisphere sampling reads the radiance at ray hits: reflective light maps or a
    /// direct-radiance voxel volume.
    #[arg(long, value_enum, default_value_t = voxgi::gi::RadianceSource::Maps)]
    gi_radiance: voxgi::gi::RadianceSource,
    /// Hierarchy level GI rays start their traversal at (thesis §4.5).
    #[arg(long, default_value_t = 1)]
    gi_start_level: u32,
    /// Iteration cap of GI rays' hierarchical traversal (too low shows as missing indirect
    /// shadows, thesis Fig. 46).
    #[arg(long, default_value_t = 1024)]
    gi_max_iterations: u32,
    /// GI rays per pixel [default: the scene's `[gi] rays`, else 16].
    #[arg(long, value_name = "N")]
    gi_rays: Option<u32>,
    /// GI ray length in meters [default: the scene's `[gi] radius_m`, else the scene's
    /// diagonal].
    #[arg(long, value_name = "M")]
    gi_radius: Option<f32>,
    /// Self-intersection offset along the normal, in voxel diagonals (thesis k1) [default: the
    /// scene's `[gi] normal_offset_voxels`, else 1].
    #[arg(long, value_name = "K1")]
    gi_normal_offset: Option<f32>,
    /// Self-intersection offset along the ray, in voxel diagonals over cos (thesis k2)
    /// [default: the scene's `[gi] ray_offset_voxels`, else 0].
    #[arg(long, value_name = "K2")]
    gi_ray_offset: Option<f32>,
    /// Geometry-aware filter radius in pixels, 0: off [default: the scene's `[gi]
    /// filter_radius`, else 4].
    #[arg(long, value_name = "R")]
    gi_filter_radius: Option<u32>,
    /// Geometry-aware filter passes, each horizontal + vertical [default: the scene's `[gi]
    /// filter_passes`, else 2].
    #[arg(long, value_name = "P")]
    gi_filter_passes: Option<u32>,
    /// Path-tracer bounces, 1..=64, or `unbounded`: 3 bounces, then Russian roulette ends each
    /// path (unbiased; capped at 64) [default: the scene's `[gi] bounces`, else 2].
    #[arg(long, value_name = "B")]
    gi_bounces: Option<voxgi::gi::Bounces>,
    /// Frames the path tracer accumulates in a headless render [default: the scene's `[gi]
    /// accumulate_frames`, else 1].
    #[arg(long, value_name = "F")]
    gi_frames: Option<u32>,
    /// Reflective light-map resolution per light view [default: the scene's `[gi]
    /// light_map_resolution`, else 256].
    #[arg(long, value_name = "L")]
    light_map_resolution: Option<u32>,
}

impl GiArgs {
    /// The flags given, for [`voxgi::scene::resolve_gi`].
    fn overrides(&self) -> GiOverrides {
        GiOverrides {
            method: self.gi,
            rays: self.gi_rays,
            bounces: self.gi_bounces,
            radius_m: self.gi_radius,
            normal_offset_voxels: self.gi_normal_offset,
            ray_offset_voxels: self.gi_ray_offset,
            filter_radius: self.gi_filter_radius,
            filter_passes: self.gi_filter_passes,
            light_map_resolution: self.light_map_resolution,
            accumulate_frames: self.gi_frames,
        }
    }

    /// The scene's `[gi]` values, overridden by the flags given.
    fn settings(&self, scene: &Scene) -> voxgi::gi::GiSettings {
        voxgi::gi::GiSettings {
            radiance_source: self.gi_radiance,
            start_level: self.gi_start_level,
            max_iterations: self.gi_max_iterations,
            ..resolve_gi(&scene.gi, &self.overrides())
        }
    }
}

/// Frame settings shared by `render` and `profile`.
#[derive(clap::Args, Clone)]
struct FrameArgs {
    #[arg(long, default_value_t = 512)]
    width: u32,
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Scene time in seconds (animations).
    #[arg(long, default_value_t = 0.0)]
    time: f32,
    #[arg(long, value_enum, default_value_t = ToneOperator::Filmic)]
    tonemap: ToneOperator,
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Shadow-map resolution (texels per side).
    #[arg(long, default_value_t = 1024)]
    shadow_resolution: u32,
    /// PCF radius in texels.
    #[arg(long, default_value_t = 1)]
    pcf_radius: u32,
    /// Shadow maps of point lights: six cube faces or two paraboloid hemispheres.
    #[arg(long, value_enum, default_value_t = PointShadow::Cube)]
    point_shadows: PointShadow,
    /// Voxelize the scene into a grid of at most N×N columns: static geometry once, dynamic
    /// objects in the frames they move (`profile` then shows those voxel passes).
    #[arg(long, value_name = "N")]
    voxels: Option<u32>,
    /// Depth layers of 128 voxels of the voxel grid.
    #[arg(long, default_value_t = 1)]
    voxel_layers: u32,
    /// Re-voxelize static geometry every frame too (measures the full voxelization).
    #[arg(long)]
    revoxelize: bool,
    /// Voxelizer: exact triangle/box test, or the thesis's texture-atlas splatting with
    /// automatic atlases (applies to --voxels, GI and --debug voxel grids).
    #[arg(long, value_enum, default_value_t = voxgi::voxel::gpu::Voxelizer::Triangle)]
    voxelizer: voxgi::voxel::gpu::Voxelizer,
    #[command(flatten)]
    gi: GiArgs,
    /// Show a voxel debug view instead of the lit image (voxelizes at 128 unless --voxels).
    #[arg(long, value_enum)]
    debug: Option<voxgi::voxel::debug_view::DebugView>,
    /// Hierarchy level shown by --debug level (0 = the voxels).
    #[arg(long, default_value_t = 0)]
    debug_level: u32,
    /// Traversal steps shown white by --debug steps.
    #[arg(long, default_value_t = 64)]
    debug_steps_scale: u32,
    /// The object whose atlas --debug atlas shows: its name or index in the scene.
    #[arg(long, default_value = "0")]
    object: String,
}

impl FrameArgs {
    /// The frame's settings; GI values not given as flags come from the scene's `[gi]`.
    fn settings(&self, scene: &Scene) -> Result<RenderSettings> {
        let mut s = RenderSettings {
            width: self.width,
            height: self.height,
            time_s: self.time,
            ..Default::default()
        };
        s.tonemap.operator = self.tonemap;
        s.tonemap.exposure = self.exposure;
        s.shadow.resolution = self.shadow_resolution;
        s.shadow.pcf_radius = self.pcf_radius;
        s.shadow.point_technique = self.point_shadows;
        let default_res = voxgi::voxel::gpu::VoxelSettings::default().max_res_xy;
        s.gi = self.gi.settings(scene);
        // GI and the voxel debug views voxelize without --voxels, honouring --voxelizer,
        // --voxel-layers and --revoxelize (the atlas view draws an atlas, not voxels).
        let atlas_view = self.debug == Some(voxgi::voxel::debug_view::DebugView::Atlas);
        let needs_voxels = s.gi.method != GiMethod::None || (self.debug.is_some() && !atlas_view);
        s.voxels = self
            .voxels
            .or(needs_voxels.then_some(default_res))
            .map(|max_res_xy| voxgi::voxel::gpu::VoxelSettings {
                max_res_xy,
                layers: self.voxel_layers,
                revoxelize_static: self.revoxelize,
                voxelizer: self.voxelizer,
            });
        let object = match self.debug {
            Some(voxgi::voxel::debug_view::DebugView::Atlas) => {
                voxgi::voxel::atlas_view::find_object(scene, &self.object)?
            }
            _ => 0,
        };
        s.debug = self
            .debug
            .map(|view| voxgi::voxel::debug_view::DebugSettings {
                view,
                level: self.debug_level,
                steps_scale: self.debug_steps_scale,
                object,
                ..Default::default()
            });
        Ok(s)
    }
}

/// `println!` that hands a closed stdout (`voxgi compare a b | head -1`) back as an error
/// instead of panicking; `main` ends quietly on it, like other CLI tools.
macro_rules! outln {
    ($($arg:tt)*) => {
        writeln!(std::io::stdout(), $($arg)*)?
    };
}

/// `print!` with the same broken-pipe handling as [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {
        write!(std::io::stdout(), $($arg)*)?
    };
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        let broken_pipe = e.chain().any(|c| {
            c.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
        });
        if broken_pipe {
            std::process::exit(0);
        }
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::ExportMitsuba {
            scene,
            output,
            width,
            height,
            time,
        } => {
            let scene = load_scene_arg(scene.as_deref())?;
            let report =
                voxgi::eval::mitsuba::export_mitsuba(&scene, time, width, height, &output)?;
            for w in &report.warnings {
                eprintln!("warning: {w}");
            }
            outln!(
                "wrote {} ({} shapes, {} triangles)",
                report.xml_path.display(),
                report.shape_count,
                report.triangle_count
            );
            Ok(())
        }
        Command::Bench(BenchCommand::Traverse {
            scene,
            resolution,
            gbuffer,
            rays,
            start_level,
            max_iterations,
            json,
        }) => {
            let scene = load_scene_arg(scene.as_deref())?;
            let ctx = context(cli.validate, cli.device)?;
            let desc = voxgi::voxel::bench::TraverseBenchDesc {
                resolution,
                gbuffer_size: gbuffer,
                rays_per_point: rays,
                params: voxgi::voxel::TraversalParams {
                    start_level,
                    max_iterations,
                },
                ..Default::default()
            };
            let report = voxgi::voxel::bench::bench_traverse(&ctx, &scene, &desc)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                out!("{}", report.table());
            }
            check_validation(&ctx)
        }
        Command::Bench(BenchCommand::Voxelize {
            scene,
            resolution,
            layers,
            repeats,
            json,
        }) => {
            let scene = load_scene_arg(scene.as_deref())?;
            let ctx = context(cli.validate, cli.device)?;
            let desc = voxgi::voxel::bench::VoxelizeBenchDesc {
                resolution,
                layers,
                repeats,
            };
            let report = voxgi::voxel::bench::bench_voxelize_atlas(&ctx, &scene, &desc)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.table());
            }
            check_validation(&ctx)
        }
        Command::Bench(BenchCommand::VoxelizeSweep {
            resolutions,
            reps,
            json,
        }) => {
            let ctx = context(cli.validate, cli.device)?;
            let desc = voxgi::voxel::bench::VoxelizeSweepDesc {
                resolutions,
                reps,
                ..Default::default()
            };
            let report = voxgi::voxel::bench::bench_voxelize_sweep(&ctx, &desc)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                out!("{}", report.table());
            }
            check_validation(&ctx)
        }
        Command::Devices => {
            out!("{}", voxgi::vk::describe_devices()?);
            Ok(())
        }
        Command::View {
            scene,
            width,
            height,
            tonemap,
            exposure,
            frames,
            resize,
            minimize_at,
            restore_after,
            screenshot,
            gi,
            debug,
            object,
        } => {
            let scene = load_scene_arg(scene.as_deref())?;
            // Checked when the viewer starts in the atlas view; the panel may switch to it
            // later, then showing this object if it exists, else the first.
            let object = match voxgi::voxel::atlas_view::find_object(&scene, &object) {
                Ok(i) => i,
                Err(e) if debug == Some(voxgi::voxel::debug_view::DebugView::Atlas) => {
                    return Err(e.into())
                }
                Err(_) => 0,
            };
            let mut settings = RenderSettings {
                debug: debug.map(|view| voxgi::voxel::debug_view::DebugSettings {
                    view,
                    object,
                    ..Default::default()
                }),
                ..Default::default()
            };
            settings.tonemap.operator = tonemap;
            settings.tonemap.exposure = exposure;
            settings.gi = gi.settings(&scene);
            let opts = voxgi::app::ViewerOptions {
                validation: cli.validate,
                device: cli.device,
                width,
                height,
                settings,
                frames,
                resize_to: resize,
                minimize_at,
                restore_after,
                screenshot,
            };
            let report = voxgi::app::run(scene, &opts)?;
            if let Some(camera) = &report.camera {
                // Pasteable into a scene file, to start there next time.
                out!("camera at exit:\n{}", camera.toml_table());
            }
            for p in &report.screenshots {
                outln!("wrote {}", p.display());
            }
            if report.skipped_minimized > 0 {
                outln!(
                    "skipped {} frames while minimized",
                    report.skipped_minimized
                );
            }
            let n = report.validation_messages.len();
            if n > 0 {
                bail!("the validation layers reported {n} message(s) (see the log above); this is a bug in voxgi, please report it");
            }
            Ok(())
        }
        Command::Compare {
            reference,
            test,
            heatmap,
            mask,
            json,
        } => compare(&reference, &test, heatmap.as_deref(), mask.as_deref(), json),
        Command::Graph {
            scene,
            demo,
            dot,
            frame,
        } => {
            let ctx = context(cli.validate, cli.device)?;
            let dump = |exec: &voxgi::graph::GraphExecutor| {
                let c = exec.compiled();
                if dot {
                    out!("{}", c.dump_dot(exec.graph()));
                } else {
                    out!("{}", c.dump_text(exec.graph()));
                }
                Ok::<(), anyhow::Error>(())
            };
            if demo {
                let demo = Demo::new(&ctx, frame.width, frame.height)?;
                let exec = demo.executor(&ctx, 1)?;
                dump(&exec)?;
                exec.destroy(&ctx);
                demo.destroy(&ctx);
            } else {
                let scene = load_scene_arg(scene.as_deref())?;
                let renderer = voxgi::render::Renderer::new(&ctx, &scene, frame.settings(&scene)?)?;
                let exec = voxgi::graph::GraphExecutor::new(&ctx, renderer.graph(), 1)?;
                dump(&exec)?;
                exec.destroy(&ctx);
                renderer.destroy(&ctx);
            }
            check_validation(&ctx)
        }
        Command::Render {
            scene,
            output,
            exr,
            frame,
            compare,
        } => {
            let scene = load_scene_arg(scene.as_deref())?;
            let ctx = context(cli.validate, cli.device)?;
            let settings = frame.settings(&scene)?;
            let out = render_image(&ctx, &scene, &settings)?;
            image::save_buffer(
                &output,
                &out.ldr,
                frame.width,
                frame.height,
                image::ColorType::Rgba8,
            )
            .with_context(|| format!("writing {}", output.display()))?;
            outln!("wrote {}", output.display());
            if let Some(path) = exr {
                out.hdr.save_exr(&path)?;
                outln!("wrote {}", path.display());
            }
            for t in &out.timings {
                outln!("  {:<16} {:>9.3} ms", t.name, t.gpu_ms);
            }
            if let Some(d) = &out.debug_description {
                outln!("{d}");
            }
            if let Some(reference) = compare {
                let r = voxgi::eval::HdrImage::load(&reference)?;
                let m = voxgi::eval::compare(&r, &out.hdr, None)?;
                print_metrics(&m)?;
            }
            check_validation(&ctx)
        }
        Command::Profile {
            scene,
            demo,
            frame,
            frames,
            warmup,
            json,
        } => {
            let ctx = context(cli.validate, cli.device)?;
            let report = if demo {
                profile_demo(&ctx, frames, warmup, frame.width, frame.height)?
            } else {
                let scene_name = scene
                    .clone()
                    .unwrap_or_else(|| voxgi::scene::DEFAULT_SCENE.into());
                let scene = load_scene_arg(scene.as_deref())?;
                let run = profile_scene(&ctx, &scene, &frame.settings(&scene)?, frames, warmup)?;
                let mut report = ProfileReport::from_frames(&ctx.info.name, &run.frames, warmup)
                    .with_setup(&run.setup);
                report.notes.push(("scene".into(), scene_name));
                report.notes.push((
                    "resolution".into(),
                    format!("{}x{}", frame.width, frame.height),
                ));
                report
                    .notes
                    .push(("transient memory".into(), run.transient_memory.summary()));
                report
                    .notes
                    .push(("culled passes".into(), run.culled_passes.join(", ")));
                report
            };
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                out!("{}", report.table());
            }
            check_validation(&ctx)
        }
    }
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

fn context(validate: bool, device: Option<String>) -> Result<Context> {
    Ok(Context::new(&ContextDesc {
        validation: validate,
        device,
        ..Default::default()
    })?)
}

fn check_validation(ctx: &Context) -> Result<()> {
    let n = ctx.validation.total();
    if n > 0 {
        bail!("the validation layers reported {n} message(s) (see the log above); this is a bug in voxgi, please report it");
    }
    Ok(())
}

fn profile_demo(
    ctx: &Context,
    frames: usize,
    warmup: usize,
    width: u32,
    height: u32,
) -> Result<ProfileReport> {
    let demo = Demo::new(ctx, width, height)?;
    let exec = demo.executor(ctx, MAX_FRAMES_IN_FLIGHT)?;
    let mut frame_loop = FrameLoop::new(
        ctx,
        MAX_FRAMES_IN_FLIGHT,
        exec.compiled().order.len() as u32,
    )?;
    let mut measured = Vec::new();
    for i in 0..warmup + frames {
        let (slot, cmd, ts, done) = frame_loop.begin(ctx)?;
        exec.record(&cmd, slot, ts);
        if i >= warmup + MAX_FRAMES_IN_FLIGHT && !done.is_empty() {
            measured.push(done);
        }
        frame_loop.submit(ctx, &[], &[])?;
    }
    measured.extend(
        frame_loop
            .finish(ctx)?
            .into_iter()
            .filter(|t| !t.is_empty()),
    );
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
    exec.destroy(ctx);
    frame_loop.destroy(ctx);
    demo.destroy(ctx);
    Ok(report)
}

fn compare(
    reference: &std::path::Path,
    test: &std::path::Path,
    heatmap: Option<&std::path::Path>,
    mask: Option<&std::path::Path>,
    json: bool,
) -> Result<()> {
    let mask = match mask {
        Some(path) => {
            let img = voxgi::eval::HdrImage::load(path)?;
            Some(
                img.data
                    .iter()
                    .map(|p| voxgi::eval::luminance(*p) > 0.5)
                    .collect::<Vec<bool>>(),
            )
        }
        None => None,
    };
    let m = voxgi::eval::compare_files(reference, test, mask.as_deref())?;
    if let Some(path) = heatmap {
        let r = voxgi::eval::HdrImage::load(reference)?;
        let t = voxgi::eval::HdrImage::load(test)?;
        let errors = voxgi::eval::flip_error_map(&r, &t)?;
        voxgi::eval::write_heatmap(path, &errors, r.width, r.height)
            .with_context(|| format!("writing the heatmap {}", path.display()))?;
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&m)?);
    } else {
        print_metrics(&m)?;
    }
    Ok(())
}

fn print_metrics(m: &voxgi::eval::Metrics) -> Result<()> {
    outln!("relMSE    {:.6}", m.rel_mse);
    outln!("PSNR      {:.2} dB", m.psnr_db);
    outln!("SSIM      {:.4}", m.ssim);
    outln!("FLIP      {:.4}", m.flip_mean);
    outln!("mean |e|  {:.6}", m.mean_abs);
    outln!("max |e|   {:.6}", m.max_abs);
    outln!("pixels    {}", m.pixels);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn render_gi(args: &[&str]) -> GiOverrides {
        let cli = Cli::try_parse_from([&["voxgi", "render"], args].concat()).expect("parses");
        match cli.command {
            Command::Render { frame, .. } => frame.gi.overrides(),
            _ => unreachable!(),
        }
    }

    fn render_settings(args: &[&str]) -> RenderSettings {
        let cli = Cli::try_parse_from([&["voxgi", "render"], args].concat()).expect("parses");
        let scene = load_scene_arg(None).expect("the built-in scene");
        match cli.command {
            Command::Render { frame, .. } => frame.settings(&scene).expect("settings"),
            _ => unreachable!(),
        }
    }

    #[test]
    fn voxel_flags_apply_to_gi_and_debug_grids_without_voxels() {
        let v = render_settings(&["--gi", "pathtrace", "--revoxelize", "--voxel-layers", "2"])
            .voxels
            .expect("GI voxelizes");
        assert!(v.revoxelize_static && v.layers == 2, "{v:?}");
        let v = render_settings(&["--debug", "voxels", "--voxelizer", "atlas"])
            .voxels
            .expect("the voxel view voxelizes");
        assert_eq!(v.voxelizer, voxgi::voxel::gpu::Voxelizer::Atlas);
        // The built-in scene's `[gi]` table path-traces; direct light needs no voxels.
        assert!(render_settings(&["--gi", "none", "--debug", "atlas"])
            .voxels
            .is_none());
        assert!(render_settings(&["--gi", "none"]).voxels.is_none());
    }

    #[test]
    fn gi_flags_not_given_leave_the_scene_values() {
        assert!(render_gi(&[]).is_empty());
        let scene = GiOverrides {
            method: Some(GiMethod::Pathtrace),
            rays: Some(4),
            bounces: Some(voxgi::gi::Bounces::Fixed(3)),
            ..Default::default()
        };
        let s = resolve_gi(&scene, &render_gi(&[]));
        assert_eq!(
            (s.method, s.rays, s.bounces),
            (GiMethod::Pathtrace, 4, voxgi::gi::Bounces::Fixed(3))
        );
        let s = resolve_gi(
            &scene,
            &render_gi(&["--gi", "hemisphere", "--gi-rays", "32", "--gi-frames", "8"]),
        );
        assert_eq!(
            (s.method, s.rays, s.bounces, s.accumulate_frames),
            (GiMethod::Hemisphere, 32, voxgi::gi::Bounces::Fixed(3), 8)
        );
    }

    #[test]
    fn every_gi_flag_maps_to_its_field() {
        let o = render_gi(&[
            "--gi",
            "pathtrace",
            "--gi-rays",
            "2",
            "--gi-bounces",
            "3",
            "--gi-radius",
            "0.5",
            "--gi-normal-offset",
            "0.25",
            "--gi-ray-offset",
            "1.5",
            "--gi-filter-radius",
            "6",
            "--gi-filter-passes",
            "7",
            "--gi-frames",
            "9",
            "--light-map-resolution",
            "128",
        ]);
        assert_eq!(
            o,
            GiOverrides {
                method: Some(GiMethod::Pathtrace),
                rays: Some(2),
                bounces: Some(voxgi::gi::Bounces::Fixed(3)),
                radius_m: Some(0.5),
                normal_offset_voxels: Some(0.25),
                ray_offset_voxels: Some(1.5),
                filter_radius: Some(6),
                filter_passes: Some(7),
                light_map_resolution: Some(128),
                accumulate_frames: Some(9),
            }
        );
        // The viewer takes the same flags.
        let cli = Cli::try_parse_from(["voxgi", "view", "--gi", "pathtrace", "--gi-bounces", "1"])
            .expect("parses");
        let Command::View { gi, .. } = cli.command else {
            unreachable!()
        };
        assert_eq!(
            (gi.gi, gi.gi_bounces, gi.gi_rays),
            (
                Some(GiMethod::Pathtrace),
                Some(voxgi::gi::Bounces::Fixed(1)),
                None
            )
        );
    }
}

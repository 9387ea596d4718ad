//! The `voxgi` command line: argument parsing only; each command is one call into
//! [`voxgi::cli`].

use anyhow::Result;
use clap::{Parser, Subcommand};
use voxgi::cli::bench::BenchCommand;
use voxgi::cli::compare::CompareArgs;
use voxgi::cli::export::ExportArgs;
use voxgi::cli::generate::GenerateArgs;
use voxgi::cli::profile::{GraphArgs, ProfileArgs};
use voxgi::cli::render::RenderArgs;
use voxgi::cli::sweep::{SweepArgs, TuneArgs};
use voxgi::cli::view::ViewArgs;
use voxgi::cli::Global;

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
    Render(RenderArgs),
    /// Runs the frame N times after warm-up and prints per-pass GPU milliseconds
    /// (median, min, max).
    Profile(ProfileArgs),
    /// Prints the compiled render graph: passes, barriers, lifetimes, transient memory.
    Graph(GraphArgs),
    /// Opens the interactive viewer: fly camera (WASD, Q/E, right mouse), a panel with per-pass
    /// GPU times, light, tone-mapping, shadow and global-illumination controls; F12 writes a
    /// screenshot.
    View(ViewArgs),
    /// Lists Vulkan devices and whether voxgi can use them.
    Devices,
    /// Benchmarks measured side by side in one GPU run.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Writes a Mitsuba 3 scene (XML + PLY meshes) identical to a voxgi scene, for reference
    /// rendering with tools/reference.
    ExportMitsuba(ExportArgs),
    /// Compares two images (EXR or PNG): relMSE, PSNR, SSIM, FLIP, mean/max absolute error.
    Compare(CompareArgs),
    /// Measures the speed/accuracy trade: every method over a grid of GI, shadow and post
    /// settings on each scene with a reference (GPU ms, transient memory, relMSE, FLIP, PSNR,
    /// SSIM) to CSV, JSON and an SVG plot of error vs time with the Pareto front, per scene.
    Sweep(SweepArgs),
    /// From a sweep's CSV, prints the most accurate configuration within a GPU-time budget
    /// as a `[gi]` table (and the `[shadow]`/`[post]` keys its grid set) to paste into the
    /// scene file.
    Tune(TuneArgs),
    /// Writes a procedural scene (OBJ, MTL, PNG textures and a scene TOML), e.g. the
    /// Sponza-scale atrium that assets/scenes/atrium.toml loads.
    Generate(GenerateArgs),
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        // A closed stdout (`voxgi compare a b | head -1`) ends quietly, like other CLI tools.
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
    let global = Global {
        validate: cli.validate,
        device: cli.device,
    };
    let out = &mut std::io::stdout();
    match cli.command {
        Command::Render(args) => voxgi::cli::render::render(&global, &args, out)?,
        Command::Profile(args) => voxgi::cli::profile::profile(&global, &args, out)?,
        Command::Graph(args) => voxgi::cli::profile::graph(&global, &args, out)?,
        Command::View(args) => voxgi::cli::view::view(&global, args, out)?,
        Command::Devices => voxgi::cli::devices::devices(out)?,
        Command::Bench(command) => voxgi::cli::bench::bench(&global, &command, out)?,
        Command::ExportMitsuba(args) => voxgi::cli::export::export_mitsuba(&args, out)?,
        Command::Compare(args) => voxgi::cli::compare::compare(&args, out)?,
        Command::Sweep(args) => voxgi::cli::sweep::sweep(&global, &args, out)?,
        Command::Tune(args) => voxgi::cli::sweep::tune_command(&args, out)?,
        Command::Generate(args) => voxgi::cli::generate::generate(&args, out)?,
    }
    Ok(())
}

//! What each `voxgi` command does, behind the argument parsing of `main.rs`: one function per
//! command, which writes its report to the `out` it is given (stdout in `main.rs`) and
//! returns a [`CliError`] that reads as advice.
//!
//! - [`args`]: the frame and GI flags several commands share, and their conversion into
//!   [`crate::render::RenderSettings`].
//! - [`render`]: `render`; [`view`]: `view`; [`profile`]: `profile` and `graph`;
//!   [`bench`]: `bench traverse|voxelize|voxelize-sweep`; [`compare`]: `compare`;
//!   [`export`]: `export-mitsuba`; [`generate`]: `generate`; [`devices`]: `devices`; [`sweep`]: `sweep` and `tune`.

pub mod args;
pub mod bench;
pub mod compare;
pub mod devices;
pub mod export;
pub mod generate;
pub mod profile;
pub mod render;
pub mod sweep;
pub mod view;

pub use args::{FrameArgs, GiArgs};

use crate::vk::{Context, ContextDesc};
use std::path::PathBuf;

/// The flags every command takes.
#[derive(Clone, Debug, Default)]
pub struct Global {
    /// Khronos validation with synchronization validation; any message fails the command.
    pub validate: bool,
    /// Vulkan device: index or part of its name.
    pub device: Option<String>,
}

/// Errors of the commands: the layers' own errors, passed through unchanged, and the
/// command line's (writing outputs, validation messages).
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error(transparent)]
    Vk(#[from] crate::vk::VkError),
    #[error(transparent)]
    Graph(#[from] crate::graph::GraphError),
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error(transparent)]
    NoSuchObject(#[from] crate::scene::NoSuchObject),
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    #[error(transparent)]
    Eval(#[from] crate::eval::EvalError),
    #[error(transparent)]
    Mitsuba(#[from] crate::export::mitsuba::MitsubaExportError),
    #[error(transparent)]
    Bench(#[from] crate::bench::BenchError),
    #[error(transparent)]
    Sweep(#[from] crate::bench::sweep::SweepError),
    #[error(transparent)]
    Tune(#[from] crate::tune::TuneError),
    #[error(transparent)]
    Plot(#[from] crate::bench::plot::PlotError),
    #[error(transparent)]
    App(#[from] crate::app::AppError),
    #[error(transparent)]
    Generate(#[from] crate::scene::atrium::GenerateError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A flag's value out of its range.
    #[error(transparent)]
    Settings(#[from] crate::limits::LimitError),
    /// SAO's value flags or its view while SAO is off.
    #[error(
        "--sao-radius, --sao-bias, --sao-contrast, --sao-epsilon and --sao-show need SAO on, and \
         it is off: add --sao (or `sao = true` in the scene's [gi] table), or leave them out"
    )]
    SaoOff,
    /// `profile --camera-path` or `bench camera-path` on a scene without a `[camera_path]`
    /// table.
    #[error(
        "{scene}: `{command}` needs a `[camera_path]` table in the scene file, and this \
         scene has none; add one (keyframes with time_s, position and look_at or direction; \
         see the format in `voxgi::scene` docs or assets/scenes/cornell_mover.toml) or choose \
         another scene"
    )]
    NoCameraPath {
        command: &'static str,
        scene: String,
    },
    /// `profile --stereo` with `--demo` or `--camera-path`.
    #[error(
        "`voxgi profile --stereo` profiles a scene's stereo frame from the scene's camera; it \
         does not combine with --demo or --camera-path: drop one of them"
    )]
    StereoProfile,
    /// Writing the report failed, e.g. a closed pipe (`voxgi compare a b | head -1`); the
    /// `io::Error` stays the source so that `main` can end quietly on a broken pipe.
    #[error("cannot write to stdout")]
    Stdout(#[source] std::io::Error),
    /// `render -o` names a file that is not a PNG (checked before the device starts).
    #[error(
        "-o {}: the output is the tone-mapped 8-bit image, written as PNG, so its name must end \
         in .png; for the linear HDR radiance add --exr {}",
        path.display(),
        path.display()
    )]
    OutputNotPng { path: PathBuf },
    /// `view --save` names a path that cannot be written (checked before the window opens).
    #[error("--save {}: {problem}", path.display())]
    SavePath { path: PathBuf, problem: String },
    #[error("writing {}", path.display())]
    WriteImage {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("writing the heatmap {}", path.display())]
    WriteHeatmap {
        path: PathBuf,
        #[source]
        source: crate::eval::EvalError,
    },
    #[error("the validation layers reported {count} message(s) (see the log above); this is a bug in voxgi, please report it")]
    Validation { count: usize },
    #[error("GPU memory was never freed: {}; this is a bug in voxgi, please report it", names.join(", "))]
    Leak { names: Vec<String> },
    /// The command failed, and its teardown then found validation messages or leaked memory
    /// too: both are reported, the command's error first.
    #[error("{error}; and then, at teardown: {teardown}")]
    ErrorThenTeardown {
        error: Box<CliError>,
        teardown: Box<CliError>,
    },
}

/// `writeln!` into a command's `out`, a failed write becoming [`CliError::Stdout`].
macro_rules! outln {
    ($out:expr, $($arg:tt)*) => {
        writeln!($out, $($arg)*).map_err($crate::cli::CliError::Stdout)?
    };
}

/// `write!` with the same error as [`outln!`].
macro_rules! out {
    ($out:expr, $($arg:tt)*) => {
        write!($out, $($arg)*).map_err($crate::cli::CliError::Stdout)?
    };
}

pub(crate) use {out, outln};

/// The Vulkan context the global flags ask for; commands get it through [`with_context`],
/// which checks its teardown on every path.
fn context(global: &Global) -> Result<Context, CliError> {
    Ok(Context::new(&ContextDesc {
        validation: global.validate,
        device: global.device.clone(),
        ..Default::default()
    })?)
}

/// Runs `body` with the context the global flags ask for, then destroys the context and fails
/// when the validation layers reported anything during the command or its teardown (objects
/// never destroyed), or when GPU memory was never freed. The check runs when `body` fails too:
/// an error path that leaks or raises a validation message is reported like a success path's
/// (the command's own error first). Everything `body` made is dropped before the check.
pub fn with_context<T>(
    global: &Global,
    body: impl FnOnce(&Context) -> Result<T, CliError>,
) -> Result<T, CliError> {
    let ctx = context(global)?;
    let result = body(&ctx);
    let teardown = check_teardown(&ctx.finish());
    match (result, teardown) {
        (Ok(value), Ok(())) => Ok(value),
        (Ok(_), Err(teardown)) => Err(teardown),
        (Err(error), Ok(())) => Err(error),
        (Err(error), Err(teardown)) => Err(CliError::ErrorThenTeardown {
            error: Box::new(error),
            teardown: Box::new(teardown),
        }),
    }
}

/// The command's verdict on what a context's life left behind ([`Context::finish`]).
pub fn check_teardown(report: &crate::vk::TeardownReport) -> Result<(), CliError> {
    if !report.validation_messages.is_empty() {
        return Err(CliError::Validation {
            count: report.validation_messages.len(),
        });
    }
    if !report.leaked_allocations.is_empty() {
        return Err(CliError::Leak {
            names: report.leaked_allocations.clone(),
        });
    }
    Ok(())
}

//! `voxgi export-mitsuba`: the same scene for Mitsuba 3, for reference renders.

use super::{outln, CliError};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `voxgi export-mitsuba`.
#[derive(clap::Args, Clone)]
pub struct ExportArgs {
    /// A built-in scene, a TOML scene file, or a glTF/OBJ model alone. Default: cornell.
    pub scene: Option<String>,
    /// Output directory.
    #[arg(short, long)]
    pub output: PathBuf,
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    #[arg(long, default_value_t = 256)]
    pub height: u32,
    /// Scene time in seconds (animations).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// The camera's projection (`--projection`, `--ortho-height`), as for `render`.
    #[command(flatten)]
    pub camera: super::args::CameraArgs,
}

/// Writes the XML and PLY files; warnings (what Mitsuba cannot show) go to stderr.
pub fn export_mitsuba(args: &ExportArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let scene = args.camera.load_scene(args.scene.as_deref())?;
    let report = crate::export::mitsuba::export_mitsuba(
        &scene,
        args.time,
        args.width,
        args.height,
        &args.output,
    )?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    outln!(
        out,
        "wrote {} ({} shapes, {} triangles)",
        report.xml_path.display(),
        report.shape_count,
        report.triangle_count
    );
    Ok(())
}

//! `voxgi render`: one headless frame to PNG (and EXR), optionally compared with a reference.

use super::args::FrameArgs;
use super::{check_validation, context, outln, CliError, Global};
use crate::render::render_image;
use crate::scene::load_scene_arg;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `voxgi render`.
#[derive(clap::Args, Clone)]
pub struct RenderArgs {
    /// A built-in scene (cornell, cornell-point) or a TOML scene file. Default: cornell.
    pub scene: Option<String>,
    /// Output PNG (tone-mapped, sRGB).
    #[arg(short, long, default_value = "voxgi.png")]
    pub output: PathBuf,
    /// Also write the linear HDR radiance (W/(m² sr)) as OpenEXR.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Compare the linear radiance with a reference EXR and print the metrics.
    #[arg(long)]
    pub compare: Option<PathBuf>,
}

/// Renders, writes the images and prints the pass times (and the metrics with `--compare`).
pub fn render(global: &Global, args: &RenderArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let frame = &args.frame;
    let scene = load_scene_arg(args.scene.as_deref())?;
    let settings = frame.settings(&scene)?;
    let ctx = context(global)?;
    let image = render_image(&ctx, &scene, &settings)?;
    image::save_buffer(
        &args.output,
        &image.ldr,
        frame.width,
        frame.height,
        image::ColorType::Rgba8,
    )
    .map_err(|source| CliError::WriteImage {
        path: args.output.clone(),
        source,
    })?;
    outln!(out, "wrote {}", args.output.display());
    if let Some(path) = &args.exr {
        image.hdr.save_exr(path)?;
        outln!(out, "wrote {}", path.display());
    }
    for t in &image.timings {
        outln!(out, "  {:<16} {:>9.3} ms", t.name, t.gpu_ms);
    }
    if let Some(d) = &image.debug_description {
        outln!(out, "{d}");
    }
    if let Some(reference) = &args.compare {
        let r = crate::eval::HdrImage::load(reference)?;
        let m = crate::eval::compare(&r, &image.hdr, None)?;
        super::compare::print_metrics(&m, out)?;
    }
    check_validation(ctx)
}

//! `voxgi compare`: image metrics of a test image against a reference.

use super::{outln, CliError};
use crate::eval::{HdrImage, Metrics};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `voxgi compare`.
#[derive(clap::Args, Clone)]
pub struct CompareArgs {
    /// The reference image.
    pub reference: PathBuf,
    /// The image under test.
    pub test: PathBuf,
    /// Writes a FLIP error heatmap (PNG).
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// An image of the same size whose bright pixels (luminance > 0.5) are excluded from
    /// every metric, e.g. the sky.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Prints the metrics (text or JSON) and writes the heatmap if asked for.
pub fn compare(args: &CompareArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let mask = match &args.mask {
        Some(path) => {
            let img = HdrImage::load(crate::assets::find(path))?;
            Some(
                img.data
                    .iter()
                    .map(|p| crate::eval::luminance(*p) > 0.5)
                    .collect::<Vec<bool>>(),
            )
        }
        None => None,
    };
    // Inputs found from the current directory, else the project's root (assets/references).
    let reference = crate::assets::find(&args.reference);
    let test = crate::assets::find(&args.test);
    let m = crate::eval::compare_files(&reference, &test, mask.as_deref())?;
    if let Some(path) = &args.heatmap {
        write_heatmap(&reference, &test, path)?;
    }
    if args.json {
        outln!(out, "{}", serde_json::to_string_pretty(&m)?);
    } else {
        print_metrics(&m, out)?;
    }
    Ok(())
}

fn write_heatmap(reference: &Path, test: &Path, path: &Path) -> Result<(), CliError> {
    let r = HdrImage::load(reference)?;
    let t = HdrImage::load(test)?;
    let errors = crate::eval::flip_error_map(&r, &t)?;
    crate::eval::write_heatmap(path, &errors, r.width, r.height).map_err(|source| {
        CliError::WriteHeatmap {
            path: path.to_owned(),
            source,
        }
    })
}

/// The metrics as `compare` and `render --compare` print them.
pub fn print_metrics(m: &Metrics, out: &mut dyn Write) -> Result<(), CliError> {
    outln!(out, "relMSE    {:.6}", m.rel_mse);
    outln!(out, "PSNR      {:.2} dB", m.psnr_db);
    outln!(out, "SSIM      {:.4}", m.ssim);
    outln!(out, "FLIP      {:.4}", m.flip_mean);
    outln!(out, "mean |e|  {:.6}", m.mean_abs);
    outln!(out, "max |e|   {:.6}", m.max_abs);
    outln!(out, "pixels    {}", m.pixels);
    Ok(())
}

//! Image evaluation: load and save HDR/LDR images, compare a render against a reference
//! (relMSE, PSNR, SSIM, FLIP, absolute errors) and write error heatmaps.
//!
//! Pure Rust apart from FLIP, which runs NVIDIA's reference C++ implementation through the
//! `nv-flip` crate. Nothing here touches Vulkan, so all of it is tier-1 tested.
//!
//! Conventions: an [`HdrImage`] holds linear Rec.709/sRGB-primaries radiance, row-major, top
//! row first. Metrics that need display-referred values (PSNR, SSIM, FLIP) clamp to `[0, 1]`
//! and sRGB-encode; the others work on linear values.

mod color;
mod error;
pub mod heatmap;
pub mod image_io;
pub mod metrics;
pub mod mitsuba;

pub use color::{luminance, srgb_decode, srgb_encode, to_srgb8};
pub use error::EvalError;
pub use heatmap::{magma_colormap, write_heatmap};
pub use image_io::HdrImage;
pub use metrics::{compare, compare_files, flip_error_map, Metrics};

#[cfg(test)]
mod tests;

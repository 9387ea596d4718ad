//! Image evaluation: compare a render against a reference (relMSE, PSNR, SSIM, FLIP,
//! absolute errors) and write error heatmaps. The images themselves, their files and sRGB
//! live in `imaging` (re-exported here); the Mitsuba exporter in `export`.
//!
//! Pure Rust apart from FLIP, which runs NVIDIA's reference C++ implementation through the
//! `nv-flip` crate. Nothing here touches Vulkan, so all of it is tier-1 tested.
//!
//! Conventions: an [`HdrImage`] holds linear Rec.709/sRGB-primaries radiance, row-major, top
//! row first. Metrics that need display-referred values (PSNR, SSIM, FLIP) clamp to `[0, 1]`
//! and sRGB-encode; the others work on linear values.

pub mod heatmap;
pub mod metrics;

pub use crate::imaging::image_io;
pub use crate::imaging::ImageError as EvalError;
pub use crate::imaging::{luminance, srgb_decode, srgb_encode, to_srgb8, HdrImage};
pub use heatmap::{magma_colormap, write_heatmap};
pub use metrics::{compare, compare_files, flip_error_map, Metrics};

#[cfg(test)]
mod tests;

//! Images and colour: the linear HDR image ([`HdrImage`]) with its EXR/PNG loading and
//! saving, sRGB encoding and luminance. Plain data and codecs, used by the scene loader
//! (sRGB textures), the renderer's read-backs and the evaluation alike.
//!
//! Conventions: an [`HdrImage`] holds linear Rec.709/sRGB-primaries radiance, row-major, top
//! row first.

pub(crate) mod color;
mod error;
pub mod image_io;

pub use color::{luminance, srgb_decode, srgb_encode, to_srgb8};
pub use error::ImageError;
pub use image_io::HdrImage;

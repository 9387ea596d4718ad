//! Loading and saving evaluation images: OpenEXR for linear HDR data, PNG for display images.

use std::fs::File;
use std::io::{BufReader, ErrorKind};
use std::path::Path;

use image::{DynamicImage, ImageFormat};

use super::color::{srgb_decode, to_srgb8};
use super::error::EvalError;

/// A linear-RGB image (sRGB / Rec.709 primaries), row-major with the top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    /// `width * height` pixels; [`HdrImage::new`] checks the length, code that builds the
    /// struct by hand must keep it.
    pub data: Vec<[f32; 3]>,
}

impl HdrImage {
    /// Wraps pixel data, checking that there is exactly one pixel per `width * height`.
    pub fn new(width: u32, height: u32, data: Vec<[f32; 3]>) -> Result<Self, EvalError> {
        let expected = pixel_count(width, height);
        if data.len() != expected {
            return Err(EvalError::LengthMismatch {
                what: "pixel data".to_owned(),
                actual: data.len(),
                expected,
                width,
                height,
            });
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// An image with every pixel set to `rgb`.
    pub fn filled(width: u32, height: u32, rgb: [f32; 3]) -> Self {
        Self {
            width,
            height,
            data: vec![rgb; pixel_count(width, height)],
        }
    }

    /// Number of pixels, `width * height`.
    pub fn pixel_count(&self) -> usize {
        pixel_count(self.width, self.height)
    }

    /// Fails with [`EvalError::LengthMismatch`] if `data` does not hold one entry per pixel
    /// (possible when the struct was built or changed by hand).
    pub fn check_len(&self, what: &str) -> Result<(), EvalError> {
        let expected = self.pixel_count();
        if self.data.len() != expected {
            return Err(EvalError::LengthMismatch {
                what: format!("{what} pixel data"),
                actual: self.data.len(),
                expected,
                width: self.width,
                height: self.height,
            });
        }
        Ok(())
    }

    /// Fails with [`EvalError::NonFinite`] (count and first pixel) if any channel is NaN or
    /// infinite. `what` names the image in the message, e.g. the file it came from.
    pub fn check_finite(&self, what: &str) -> Result<(), EvalError> {
        let mut bad = self
            .data
            .iter()
            .enumerate()
            .filter(|(_, p)| p.iter().any(|c| !c.is_finite()));
        if let Some((first, _)) = bad.next() {
            let width = self.width.max(1) as usize;
            return Err(EvalError::NonFinite {
                what: what.to_owned(),
                count: 1 + bad.count(),
                x: (first % width) as u32,
                y: (first / width) as u32,
            });
        }
        Ok(())
    }

    /// Loads an OpenEXR file with RGB or RGBA float (or half) channels; alpha is dropped.
    /// Rejects files containing NaN or infinite values.
    pub fn load_exr(path: impl AsRef<Path>) -> Result<Self, EvalError> {
        let path = path.as_ref();
        let (decoded, format) = decode(path)?;
        if format != ImageFormat::OpenExr {
            return Err(EvalError::UnsupportedFormat {
                path: path.to_owned(),
                detail: format!("it is {format:?}, expected OpenEXR"),
            });
        }
        let image = from_rgb32f(decoded.into_rgb32f(), |c| c);
        image.check_finite(&format!("image file {}", path.display()))?;
        Ok(image)
    }

    /// Loads an 8- or 16-bit PNG and decodes its sRGB values to linear; alpha is dropped.
    pub fn load_png(path: impl AsRef<Path>) -> Result<Self, EvalError> {
        let path = path.as_ref();
        let (decoded, format) = decode(path)?;
        if format != ImageFormat::Png {
            return Err(EvalError::UnsupportedFormat {
                path: path.to_owned(),
                detail: format!("it is {format:?}, expected PNG"),
            });
        }
        Ok(from_rgb32f(decoded.into_rgb32f(), srgb_decode))
    }

    /// Loads an OpenEXR (linear) or PNG (sRGB, decoded to linear) file, chosen by its content.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, EvalError> {
        let path = path.as_ref();
        match guess_format(path)? {
            ImageFormat::OpenExr => Self::load_exr(path),
            ImageFormat::Png => Self::load_png(path),
            other => Err(EvalError::UnsupportedFormat {
                path: path.to_owned(),
                detail: format!("it is {other:?}"),
            }),
        }
    }

    /// Writes the image as a 32-bit float RGB OpenEXR file; values round-trip bit for bit.
    pub fn save_exr(&self, path: impl AsRef<Path>) -> Result<(), EvalError> {
        let path = path.as_ref();
        self.check_len(&format!("image for {}", path.display()))?;
        let flat: Vec<f32> = self.data.iter().flatten().copied().collect();
        let buffer =
            image::Rgb32FImage::from_raw(self.width, self.height, flat).ok_or_else(|| {
                EvalError::LengthMismatch {
                    what: format!("image for {}", path.display()),
                    actual: self.data.len(),
                    expected: self.pixel_count(),
                    width: self.width,
                    height: self.height,
                }
            })?;
        buffer
            .save_with_format(path, ImageFormat::OpenExr)
            .map_err(|e| codec_error(path, e))
    }

    /// Writes an image whose linear values are already display-referred (`[0, 1]`; values
    /// outside are clamped) as an 8-bit sRGB PNG.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), EvalError> {
        self.save_png_tonemapped(path, |rgb| rgb)
    }

    /// Writes an 8-bit sRGB PNG after mapping each pixel through `tone_map`, which takes linear
    /// scene radiance and returns linear display values in `[0, 1]` (clamped afterwards);
    /// the sRGB encoding is applied here, not by the closure.
    pub fn save_png_tonemapped(
        &self,
        path: impl AsRef<Path>,
        tone_map: impl Fn([f32; 3]) -> [f32; 3],
    ) -> Result<(), EvalError> {
        let path = path.as_ref();
        self.check_len(&format!("image for {}", path.display()))?;
        let bytes: Vec<u8> = self
            .data
            .iter()
            .flat_map(|&p| tone_map(p).map(to_srgb8))
            .collect();
        save_rgb8_png(path, self.width, self.height, bytes)
    }
}

/// Writes raw 8-bit RGB rows (already display-encoded) as a PNG.
pub(crate) fn save_rgb8_png(
    path: &Path,
    width: u32,
    height: u32,
    bytes: Vec<u8>,
) -> Result<(), EvalError> {
    let actual = bytes.len() / 3;
    let buffer = image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| {
        EvalError::LengthMismatch {
            what: format!("image for {}", path.display()),
            actual,
            expected: pixel_count(width, height),
            width,
            height,
        }
    })?;
    buffer
        .save_with_format(path, ImageFormat::Png)
        .map_err(|e| codec_error(path, e))
}

fn pixel_count(width: u32, height: u32) -> usize {
    width as usize * height as usize
}

fn from_rgb32f(buffer: image::Rgb32FImage, per_channel: impl Fn(f32) -> f32) -> HdrImage {
    let (width, height) = buffer.dimensions();
    let data = buffer
        .pixels()
        .map(|p| p.0.map(&per_channel))
        .collect::<Vec<_>>();
    HdrImage {
        width,
        height,
        data,
    }
}

fn open(path: &Path) -> Result<image::ImageReader<BufReader<File>>, EvalError> {
    let file = File::open(path).map_err(|source| match source.kind() {
        ErrorKind::NotFound => EvalError::MissingFile {
            path: path.to_owned(),
        },
        _ => EvalError::Io {
            path: path.to_owned(),
            source,
        },
    })?;
    image::ImageReader::new(BufReader::new(file))
        .with_guessed_format()
        .map_err(|source| EvalError::Io {
            path: path.to_owned(),
            source,
        })
}

fn guess_format(path: &Path) -> Result<ImageFormat, EvalError> {
    open(path)?
        .format()
        .ok_or_else(|| EvalError::UnsupportedFormat {
            path: path.to_owned(),
            detail: "unrecognised file signature".to_owned(),
        })
}

fn decode(path: &Path) -> Result<(DynamicImage, ImageFormat), EvalError> {
    let reader = open(path)?;
    let format = reader
        .format()
        .ok_or_else(|| EvalError::UnsupportedFormat {
            path: path.to_owned(),
            detail: "unrecognised file signature".to_owned(),
        })?;
    let decoded = reader.decode().map_err(|e| codec_error(path, e))?;
    Ok((decoded, format))
}

fn codec_error(path: &Path, error: image::ImageError) -> EvalError {
    match error {
        image::ImageError::IoError(source) => EvalError::Io {
            path: path.to_owned(),
            source,
        },
        image::ImageError::Unsupported(detail) => EvalError::UnsupportedFormat {
            path: path.to_owned(),
            detail: detail.to_string(),
        },
        other => EvalError::Codec {
            path: path.to_owned(),
            source: other,
        },
    }
}

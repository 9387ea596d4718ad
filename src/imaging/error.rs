use std::path::PathBuf;

/// Everything that can go wrong while loading, comparing or writing images (the evaluation
/// names it `eval::EvalError`).
///
/// Messages are meant for the person running `voxgi`: they say which file or image, what is
/// wrong with it, and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error(
        "image file {} does not exist: check the path, or render / regenerate it first",
        path.display()
    )]
    MissingFile { path: PathBuf },

    #[error("could not read or write {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    #[error(
        "{} is not a supported image ({detail}): use an OpenEXR file with RGB or RGBA float \
         channels for HDR images, or an 8/16-bit PNG for LDR images",
        path.display()
    )]
    UnsupportedFormat { path: PathBuf, detail: String },

    #[error("could not decode or encode {}: {source}", path.display())]
    Codec {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },

    #[error(
        "{what} has {count} non-finite (NaN or infinite) value(s), the first at pixel \
         ({x}, {y}): fix the renderer output (or the reference) before comparing"
    )]
    NonFinite {
        what: String,
        count: usize,
        x: u32,
        y: u32,
    },

    #[error(
        "size mismatch: reference {reference} is {ref_width}x{ref_height} but test {test} is \
         {test_width}x{test_height}: render the test image at the reference resolution"
    )]
    SizeMismatch {
        reference: String,
        test: String,
        ref_width: u32,
        ref_height: u32,
        test_width: u32,
        test_height: u32,
    },

    #[error(
        "{what} has {actual} entries but the image is {width}x{height} ({expected} pixels): \
         build it with one entry per pixel, row-major"
    )]
    LengthMismatch {
        what: String,
        actual: usize,
        expected: usize,
        width: u32,
        height: u32,
    },

    #[error("the mask excludes every pixel of {width}x{height}: there is nothing to compare")]
    EmptyMask { width: u32, height: u32 },
}

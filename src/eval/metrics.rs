//! Image-quality metrics of a render against a reference.
//!
//! | metric      | works on                               | identical images |
//! |-------------|----------------------------------------|------------------|
//! | `rel_mse`   | linear RGB                             | 0                |
//! | `psnr_db`   | clamped, sRGB-encoded RGB              | [`PSNR_CAP_DB`]  |
//! | `ssim`      | luma of clamped, sRGB-encoded RGB      | 1                |
//! | `flip_mean` | clamped, sRGB-encoded 8-bit RGB (LDR)  | 0                |
//! | `mean_abs`, `max_abs` | linear RGB                   | 0                |

use std::path::Path;

use serde::Serialize;

use super::EvalError;
use crate::imaging::color::display;
use crate::imaging::{luminance, to_srgb8, HdrImage};

/// ε in the relMSE denominator. It keeps near-black reference pixels from dominating the mean;
/// the denoising literature uses 1e-3 to 1e-2 (relMSE as introduced by Rousselle, Knaus and
/// Zwicker, "Adaptive sampling and reconstruction using greedy error minimization",
/// SIGGRAPH Asia 2011; ε = 1e-2 as in e.g. Bako et al., "Kernel-predicting convolutional
/// networks for denoising Monte Carlo renderings", SIGGRAPH 2017).
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// PSNR reported for identical images (MSE 0), and the largest PSNR ever reported, so the
/// value stays a finite number in JSON (serde_json writes infinity as `null`). 100 dB is an
/// MSE of 1e-10 on `[0, 1]` values, far below 8-bit quantisation (about 48 dB).
pub const PSNR_CAP_DB: f64 = 100.0;

/// Viewing condition for FLIP: 67 pixels per degree, FLIP's default (a 0.7 m wide 4K monitor
/// seen from 0.7 m; Andersson et al. 2020, section 4).
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// SSIM window: Gaussian, σ = 1.5 pixels, 11×11 taps (Wang et al. 2004, section III-C).
const SSIM_SIGMA: f64 = 1.5;
const SSIM_RADIUS: usize = 5;
/// SSIM stabilisers C1 = (K1·L)², C2 = (K2·L)² with K1 = 0.01, K2 = 0.03 and dynamic range
/// L = 1 (Wang et al. 2004, eq. 13 and section III-C).
const SSIM_C1: f64 = 0.01 * 0.01;
const SSIM_C2: f64 = 0.03 * 0.03;

/// Errors of a test image against a reference, over the pixels the mask keeps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Relative MSE: mean over pixels and channels of (t − r)² / (r² + ε), with
    /// ε = [`REL_MSE_EPSILON`], on linear values.
    pub rel_mse: f64,
    /// PSNR in dB of the clamped, sRGB-encoded images (peak 1): 10·log10(1 / MSE), capped at
    /// [`PSNR_CAP_DB`].
    pub psnr_db: f64,
    /// Mean SSIM (Wang et al., "Image quality assessment: from error visibility to structural
    /// similarity", IEEE TIP 2004) of the Rec.709 luma of the clamped, sRGB-encoded images.
    /// Windows are 11×11 Gaussians (σ = 1.5) cut at the image border and around masked pixels
    /// and renormalised, so every kept pixel has a value (the paper's reference code instead
    /// drops the 5-pixel border).
    pub ssim: f64,
    /// Mean LDR-FLIP error (Andersson et al., "FLIP: A Difference Evaluator for Alternating
    /// Images", HPG 2020) of the clamped, sRGB-encoded, 8-bit quantised images at
    /// [`FLIP_PIXELS_PER_DEGREE`], computed by NVIDIA's implementation (`nv-flip`). HDR-FLIP is
    /// not used: tone-map before comparing if highlights above 1 matter.
    pub flip_mean: f64,
    /// Mean absolute error over pixels and channels, linear.
    pub mean_abs: f64,
    /// Largest absolute error over pixels and channels, linear.
    pub max_abs: f64,
    /// Number of pixels compared (those the mask keeps).
    pub pixels: usize,
}

/// Compares `test` against `reference`.
///
/// `mask`, if given, has one entry per pixel (row-major); `true` **excludes** that pixel
/// (e.g. sky or background) from every metric. Excluded pixels also do not leak into their
/// neighbours' SSIM windows or FLIP filters: the test image takes the reference's values there.
///
/// Fails if the sizes differ, the mask has the wrong length or excludes every pixel, or either
/// image has non-finite values.
pub fn compare(
    reference: &HdrImage,
    test: &HdrImage,
    mask: Option<&[bool]>,
) -> Result<Metrics, EvalError> {
    compare_named(reference, "image", test, "image", mask)
}

/// Loads two files with [`HdrImage::load`] (EXR linear, PNG sRGB-decoded) and [`compare`]s
/// them; errors name the files.
pub fn compare_files(
    reference: impl AsRef<Path>,
    test: impl AsRef<Path>,
    mask: Option<&[bool]>,
) -> Result<Metrics, EvalError> {
    let (reference, test) = (reference.as_ref(), test.as_ref());
    let reference_image = HdrImage::load(reference)?;
    let test_image = HdrImage::load(test)?;
    compare_named(
        &reference_image,
        &reference.display().to_string(),
        &test_image,
        &test.display().to_string(),
        mask,
    )
}

/// Per-pixel LDR-FLIP error in `[0, 1]` (row-major), e.g. for [`super::write_heatmap`].
/// Same preprocessing as [`Metrics::flip_mean`].
pub fn flip_error_map(reference: &HdrImage, test: &HdrImage) -> Result<Vec<f32>, EvalError> {
    validate(reference, "image", test, "image")?;
    Ok(flip_map(reference, test))
}

fn compare_named(
    reference: &HdrImage,
    reference_name: &str,
    test: &HdrImage,
    test_name: &str,
    mask: Option<&[bool]>,
) -> Result<Metrics, EvalError> {
    validate(reference, reference_name, test, test_name)?;
    let (width, height) = (reference.width, reference.height);
    let keep: Vec<bool> = match mask {
        Some(mask) => {
            if mask.len() != reference.pixel_count() {
                return Err(EvalError::LengthMismatch {
                    what: "mask".to_owned(),
                    actual: mask.len(),
                    expected: reference.pixel_count(),
                    width,
                    height,
                });
            }
            mask.iter().map(|&excluded| !excluded).collect()
        }
        None => vec![true; reference.pixel_count()],
    };
    let pixels = keep.iter().filter(|&&k| k).count();
    if pixels == 0 {
        return Err(EvalError::EmptyMask { width, height });
    }

    let mut rel_se = 0.0;
    let mut display_se = 0.0;
    let mut abs_sum = 0.0;
    let mut max_abs: f64 = 0.0;
    let kept = reference.data.iter().zip(&test.data).zip(&keep);
    for ((r, t), _) in kept.filter(|(_, &k)| k) {
        for c in 0..3 {
            let (rc, tc) = (f64::from(r[c]), f64::from(t[c]));
            let diff = tc - rc;
            rel_se += diff * diff / (rc * rc + REL_MSE_EPSILON);
            abs_sum += diff.abs();
            max_abs = max_abs.max(diff.abs());
            let display_diff = f64::from(display(t[c])) - f64::from(display(r[c]));
            display_se += display_diff * display_diff;
        }
    }
    let samples = (3 * pixels) as f64;
    let display_mse = display_se / samples;
    let psnr_db = if display_mse > 0.0 {
        (10.0 * (1.0 / display_mse).log10()).min(PSNR_CAP_DB)
    } else {
        PSNR_CAP_DB
    };

    // Masked pixels take the reference's values so FLIP's spatial filters see no error there.
    let test_kept;
    let test = if mask.is_some() {
        test_kept = HdrImage {
            width,
            height,
            data: reference
                .data
                .iter()
                .zip(&test.data)
                .zip(&keep)
                .map(|((&r, &t), &k)| if k { t } else { r })
                .collect(),
        };
        &test_kept
    } else {
        test
    };
    let flip = flip_map(reference, test);
    let flip_sum: f64 = flip
        .iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(&e, _)| f64::from(e))
        .sum();

    Ok(Metrics {
        rel_mse: rel_se / samples,
        psnr_db,
        ssim: mean_ssim(reference, test, &keep),
        flip_mean: flip_sum / pixels as f64,
        mean_abs: abs_sum / samples,
        max_abs,
        pixels,
    })
}

fn validate(
    reference: &HdrImage,
    reference_name: &str,
    test: &HdrImage,
    test_name: &str,
) -> Result<(), EvalError> {
    let reference_what = format!("reference {reference_name}");
    let test_what = format!("test {test_name}");
    reference.check_len(&reference_what)?;
    test.check_len(&test_what)?;
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(EvalError::SizeMismatch {
            reference: reference_name.to_owned(),
            test: test_name.to_owned(),
            ref_width: reference.width,
            ref_height: reference.height,
            test_width: test.width,
            test_height: test.height,
        });
    }
    reference.check_finite(&reference_what)?;
    test.check_finite(&test_what)
}

/// LDR-FLIP error map; both images have the same, validated size.
fn flip_map(reference: &HdrImage, test: &HdrImage) -> Vec<f32> {
    if reference.data.is_empty() {
        return Vec::new();
    }
    let to_flip = |image: &HdrImage| {
        let bytes: Vec<u8> = image.data.iter().flat_map(|p| p.map(to_srgb8)).collect();
        nv_flip::FlipImageRgb8::with_data(image.width, image.height, &bytes)
    };
    nv_flip::flip(to_flip(reference), to_flip(test), FLIP_PIXELS_PER_DEGREE).to_vec()
}

/// Mean SSIM over kept pixels; windows are weighted by the Gaussian times the keep mask and
/// renormalised (see [`Metrics::ssim`]).
fn mean_ssim(reference: &HdrImage, test: &HdrImage, keep: &[bool]) -> f64 {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let luma = |p: &[f32; 3]| f64::from(luminance(p.map(display)));
    // Window sums of weight, x, y, x², y², xy, each premultiplied by the keep weight.
    let mut fields: [Vec<f64>; 6] = Default::default();
    for field in &mut fields {
        field.reserve_exact(w * h);
    }
    for ((r, t), &k) in reference.data.iter().zip(&test.data).zip(keep) {
        let m = if k { 1.0 } else { 0.0 };
        let (x, y) = (luma(r), luma(t));
        for (field, value) in fields.iter_mut().zip([1.0, x, y, x * x, y * y, x * y]) {
            field.push(m * value);
        }
    }
    let kernel = gaussian_kernel();
    for field in &mut fields {
        *field = blur(field, w, h, &kernel);
    }
    let [weight, sx, sy, sxx, syy, sxy] = &fields;

    let mut total = 0.0;
    let mut count = 0usize;
    for i in (0..w * h).filter(|&i| keep[i]) {
        // A kept pixel is in its own window with a positive weight.
        let norm = weight[i];
        let (mx, my) = (sx[i] / norm, sy[i] / norm);
        let vx = sxx[i] / norm - mx * mx;
        let vy = syy[i] / norm - my * my;
        let cov = sxy[i] / norm - mx * my;
        total += ((2.0 * mx * my + SSIM_C1) * (2.0 * cov + SSIM_C2))
            / ((mx * mx + my * my + SSIM_C1) * (vx + vy + SSIM_C2));
        count += 1;
    }
    if count == 0 {
        1.0
    } else {
        total / count as f64
    }
}

fn gaussian_kernel() -> Vec<f64> {
    let taps: Vec<f64> = (0..=2 * SSIM_RADIUS)
        .map(|i| {
            let d = i as f64 - SSIM_RADIUS as f64;
            (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp()
        })
        .collect();
    let sum: f64 = taps.iter().sum();
    taps.into_iter().map(|t| t / sum).collect()
}

/// Separable convolution with zero outside the image (the weight field carries the
/// renormalisation).
fn blur(field: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let radius = kernel.len() / 2;
    let mut rows = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let lo = x.saturating_sub(radius);
            let hi = (x + radius).min(w - 1);
            rows[y * w + x] = (lo..=hi)
                .map(|sx| kernel[sx + radius - x] * field[y * w + sx])
                .sum();
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        let lo = y.saturating_sub(radius);
        let hi = (y + radius).min(h - 1);
        for x in 0..w {
            out[y * w + x] = (lo..=hi)
                .map(|sy| kernel[sy + radius - y] * rows[sy * w + x])
                .sum();
        }
    }
    out
}

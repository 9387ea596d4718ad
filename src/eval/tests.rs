//! Tests of the evaluation module against analytically known answers.

use std::path::PathBuf;

use super::metrics::{PSNR_CAP_DB, REL_MSE_EPSILON};
use super::*;

/// A scratch directory unique to this process and test, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("voxgi_eval_{}_{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    fn file(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Numerical Recipes LCG; uniform in [0, 1).
struct Lcg(u32);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// A smooth, structured image in roughly [0.05, 0.65] linear.
fn textured(width: u32, height: u32) -> HdrImage {
    let data = (0..height)
        .flat_map(|y| {
            (0..width).map(move |x| {
                let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
                let s = 0.35 + 0.3 * (6.0 * u).sin() * (4.0 * v).cos();
                [s, 0.8 * s + 0.05 * u, 0.5 * s + 0.1 * v]
            })
        })
        .collect();
    HdrImage::new(width, height, data).unwrap()
}

fn assert_rel_close(actual: f64, expected: f64, what: &str) {
    let rel = ((actual - expected) / expected).abs();
    assert!(
        rel < 1e-6,
        "{what}: {actual} vs expected {expected} (rel {rel})"
    );
}

#[test]
fn identical_images_have_zero_error() {
    let image = textured(32, 24);
    let m = compare(&image, &image, None).unwrap();
    assert_eq!(m.rel_mse, 0.0);
    assert_eq!(m.mean_abs, 0.0);
    assert_eq!(m.max_abs, 0.0);
    assert_eq!(m.ssim, 1.0);
    assert_eq!(m.flip_mean, 0.0);
    assert_eq!(m.psnr_db, PSNR_CAP_DB);
    assert_eq!(m.pixels, 32 * 24);
    // The cap keeps JSON numeric.
    let json = serde_json::to_string(&m).unwrap();
    assert!(json.contains("\"psnr_db\":100.0"), "{json}");
}

#[test]
fn relative_scale_gives_analytic_rel_mse() {
    // Dyadic values so that r·(1+δ) is exact in f32.
    for (r, delta) in [(0.5f32, 0.125f32), (2.0, -0.25), (0.0625, 0.5)] {
        let reference = HdrImage::filled(16, 16, [r; 3]);
        let test = HdrImage::filled(16, 16, [r * (1.0 + delta); 3]);
        let m = compare(&reference, &test, None).unwrap();
        let (r, delta) = (f64::from(r), f64::from(delta));
        let expected = (r * delta).powi(2) / (r * r + REL_MSE_EPSILON);
        assert_rel_close(m.rel_mse, expected, "relMSE");
        assert_rel_close(m.mean_abs, (r * delta).abs(), "mean_abs");
        assert_rel_close(m.max_abs, (r * delta).abs(), "max_abs");
    }
}

#[test]
fn additive_offset_gives_analytic_rel_mse_and_psnr() {
    let (r, offset) = (0.25f32, 0.0625f32);
    let reference = HdrImage::filled(16, 8, [r; 3]);
    let test = HdrImage::filled(16, 8, [r + offset; 3]);
    let m = compare(&reference, &test, None).unwrap();
    let (r64, o64) = (f64::from(r), f64::from(offset));
    assert_rel_close(
        m.rel_mse,
        o64 * o64 / (r64 * r64 + REL_MSE_EPSILON),
        "relMSE",
    );

    // PSNR is on the sRGB-encoded values: constant difference d gives 10·log10(1/d²).
    let d = f64::from(srgb_encode(r + offset)) - f64::from(srgb_encode(r));
    assert_rel_close(m.psnr_db, -20.0 * d.log10(), "PSNR");
    // Constant images have no structure: SSIM reduces to the luminance term.
    assert!(m.ssim < 1.0 && m.ssim > 0.9, "ssim {}", m.ssim);
    assert!(m.flip_mean > 0.0);
}

#[test]
fn rel_mse_mixes_channels_per_channel() {
    // Only one channel of one pixel differs: its term is averaged over 3·N samples.
    let reference = HdrImage::filled(4, 4, [1.0, 0.5, 0.25]);
    let mut test = reference.clone();
    test.data[5][1] = 0.75;
    let m = compare(&reference, &test, None).unwrap();
    let expected = 0.25f64.powi(2) / (0.25 + REL_MSE_EPSILON) / 48.0;
    assert_rel_close(m.rel_mse, expected, "relMSE");
    assert_rel_close(m.max_abs, 0.25, "max_abs");
}

#[test]
fn masked_pixels_do_not_count() {
    let (w, h) = (24u32, 20u32);
    let reference = textured(w, h);
    let mut test = reference.clone();
    let mut mask = vec![false; (w * h) as usize];
    // Exclude a block (the "sky") and perturb only inside it, wildly.
    for y in 0..8 {
        for x in 4..20 {
            let i = (y * w + x) as usize;
            mask[i] = true;
            test.data[i] = [50.0, 0.0, 3.0];
        }
    }
    let m = compare(&reference, &test, Some(&mask)).unwrap();
    assert_eq!(m.pixels, (w * h - 8 * 16) as usize);
    assert_eq!(m.rel_mse, 0.0);
    assert_eq!(m.max_abs, 0.0);
    assert_eq!(m.ssim, 1.0);
    assert_eq!(m.flip_mean, 0.0);
    assert_eq!(m.psnr_db, PSNR_CAP_DB);

    // Without the mask the same pair is clearly different.
    let unmasked = compare(&reference, &test, None).unwrap();
    assert!(unmasked.rel_mse > 1.0 && unmasked.ssim < 0.9 && unmasked.flip_mean > 0.05);
}

#[test]
fn mask_errors_are_reported() {
    let image = textured(8, 8);
    let err = compare(&image, &image, Some(&[false; 10])).unwrap_err();
    assert!(err.to_string().contains("mask has 10 entries"), "{err}");
    let err = compare(&image, &image, Some(&[true; 64])).unwrap_err();
    assert!(matches!(err, EvalError::EmptyMask { .. }), "{err}");
}

#[test]
fn ssim_decreases_with_noise_amplitude() {
    let reference = textured(48, 40);
    let mut rng = Lcg(12345);
    let noise: Vec<[f32; 3]> = (0..reference.pixel_count())
        .map(|_| [rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5])
        .collect();
    let mut previous = compare(&reference, &reference, None).unwrap();
    for amplitude in [0.005f32, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4] {
        let data = reference
            .data
            .iter()
            .zip(&noise)
            .map(|(r, n)| [0, 1, 2].map(|c| r[c] + amplitude * n[c]))
            .collect();
        let test = HdrImage::new(reference.width, reference.height, data).unwrap();
        let m = compare(&reference, &test, None).unwrap();
        assert!(
            m.ssim < previous.ssim,
            "amplitude {amplitude}: ssim {} not below {}",
            m.ssim,
            previous.ssim
        );
        assert!(m.rel_mse > previous.rel_mse && m.psnr_db < previous.psnr_db);
        assert!(m.flip_mean >= previous.flip_mean, "amplitude {amplitude}");
        previous = m;
    }
    assert!(
        previous.ssim < 0.5,
        "heavy noise still scores {}",
        previous.ssim
    );
}

#[test]
fn flip_error_map_is_zero_for_identical_and_positive_where_changed() {
    let reference = textured(32, 32);
    let map = flip_error_map(&reference, &reference).unwrap();
    assert_eq!(map.len(), 32 * 32);
    assert!(map.iter().all(|&e| e == 0.0));

    let mut test = reference.clone();
    test.data[16 * 32 + 16] = [1.0, 0.0, 0.0];
    let map = flip_error_map(&reference, &test).unwrap();
    let peak = map.iter().copied().fold(0.0f32, f32::max);
    // FLIP blurs a lone pixel spatially, so its error is well below 1.
    assert!(peak > 0.1 && peak <= 1.0, "peak {peak}");
    assert_eq!(map[16 * 32 + 16], peak);
    assert!(map[0] < 1e-3, "far corner {}", map[0]);
}

#[test]
fn size_mismatch_names_both_sizes() {
    let err = compare(&textured(4, 4), &textured(8, 4), None).unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains("4x4") && message.contains("8x4"),
        "{message}"
    );

    let dir = TempDir::new("size");
    let (a, b) = (dir.file("ref.exr"), dir.file("test.exr"));
    textured(4, 4).save_exr(&a).unwrap();
    textured(8, 4).save_exr(&b).unwrap();
    let message = compare_files(&a, &b, None).unwrap_err().to_string();
    for needle in [a.display().to_string(), b.display().to_string()] {
        assert!(message.contains(&needle), "{message}");
    }
}

#[test]
fn non_finite_pixels_are_rejected_with_count_and_position() {
    let reference = textured(8, 6);
    let mut test = reference.clone();
    test.data[2 * 8 + 3] = [0.0, f32::NAN, 0.0];
    test.data[5 * 8 + 1] = [f32::INFINITY, 0.0, 0.0];
    let message = compare(&reference, &test, None).unwrap_err().to_string();
    assert!(message.contains("test image has 2 non-finite"), "{message}");
    assert!(message.contains("(3, 2)"), "{message}");

    // Loading such a file fails and names it.
    let dir = TempDir::new("nan");
    let path = dir.file("nan.exr");
    test.save_exr(&path).unwrap();
    let message = HdrImage::load_exr(&path).unwrap_err().to_string();
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert!(message.contains("2 non-finite") && message.contains("(3, 2)"));
}

#[test]
fn missing_and_unsupported_files_are_named() {
    let dir = TempDir::new("missing");
    let missing = dir.file("does_not_exist.exr");
    for err in [
        HdrImage::load_exr(&missing).unwrap_err(),
        HdrImage::load_png(&missing).unwrap_err(),
        HdrImage::load(&missing).unwrap_err(),
    ] {
        assert!(matches!(err, EvalError::MissingFile { .. }), "{err}");
        assert!(err.to_string().contains(&missing.display().to_string()));
    }

    let text = dir.file("notes.exr");
    std::fs::write(&text, "not an image").unwrap();
    let err = HdrImage::load_exr(&text).unwrap_err();
    assert!(matches!(err, EvalError::UnsupportedFormat { .. }), "{err}");
    assert!(err.to_string().contains("notes.exr"), "{err}");

    let png = dir.file("ldr.png");
    HdrImage::filled(2, 2, [0.5; 3]).save_png(&png).unwrap();
    let err = HdrImage::load_exr(&png).unwrap_err();
    assert!(err.to_string().contains("expected OpenEXR"), "{err}");
}

#[test]
fn exr_round_trip_is_bitwise() {
    let mut rng = Lcg(7);
    let data: Vec<[f32; 3]> = (0..37 * 19)
        .map(|i| {
            let scale = [1e-6, 1.0, 1e4][i % 3];
            [rng.next() * scale, rng.next() - 0.25, rng.next() * 100.0]
        })
        .collect();
    let image = HdrImage::new(37, 19, data).unwrap();
    let dir = TempDir::new("exr");
    let path = dir.file("round.exr");
    image.save_exr(&path).unwrap();
    for loaded in [
        HdrImage::load_exr(&path).unwrap(),
        HdrImage::load(&path).unwrap(),
    ] {
        assert_eq!((loaded.width, loaded.height), (37, 19));
        let bits = |img: &HdrImage| -> Vec<u32> {
            img.data.iter().flatten().map(|c| c.to_bits()).collect()
        };
        assert_eq!(bits(&loaded), bits(&image));
    }
}

#[test]
fn png_round_trip_within_quantisation() {
    let dir = TempDir::new("png");
    // Values on the 8-bit sRGB grid come back exactly (up to float rounding).
    let data: Vec<[f32; 3]> = (0..256u32)
        .map(|k| {
            let v = |k: u32| srgb_decode((k % 256) as f32 / 255.0);
            [v(k), v(k * 7 + 3), v(255 - k)]
        })
        .collect();
    let grid = HdrImage::new(16, 16, data).unwrap();
    let path = dir.file("grid.png");
    grid.save_png(&path).unwrap();
    let loaded = HdrImage::load_png(&path).unwrap();
    assert_eq!((loaded.width, loaded.height), (16, 16));
    for (a, b) in loaded.data.iter().flatten().zip(grid.data.iter().flatten()) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }

    // Arbitrary values come back within half an 8-bit step in encoded space; out-of-range clamps.
    let image = textured(20, 10);
    image.save_png(&path).unwrap();
    let loaded = HdrImage::load(&path).unwrap();
    for (a, b) in loaded
        .data
        .iter()
        .flatten()
        .zip(image.data.iter().flatten())
    {
        let step = (srgb_encode(*a) - srgb_encode(b.clamp(0.0, 1.0))).abs();
        assert!(step <= 0.5 / 255.0 + 1e-6, "{a} vs {b}");
    }

    // The tone-map closure runs on linear values and its output is encoded to sRGB.
    HdrImage::filled(3, 2, [4.0, 1.0, 0.0])
        .save_png_tonemapped(&path, |p| p.map(|c| c / (1.0 + c)))
        .unwrap();
    let png = image::open(&path).unwrap().into_rgb8();
    assert_eq!(
        png.get_pixel(2, 1).0,
        [to_srgb8(0.8), to_srgb8(0.5), to_srgb8(0.0)]
    );
}

#[test]
fn hdr_image_checks_its_length() {
    let err = HdrImage::new(3, 3, vec![[0.0; 3]; 8]).unwrap_err();
    assert!(err.to_string().contains("8 entries"), "{err}");
    let bad = HdrImage {
        width: 3,
        height: 3,
        data: vec![[0.0; 3]; 8],
    };
    assert!(compare(&bad, &bad, None).is_err());
}

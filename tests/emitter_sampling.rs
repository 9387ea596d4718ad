//! The path tracer's next-event estimation toward emissive triangles (`gi.emitter_sampling`):
//! with and without it the path tracer converges to the same radiance, and with it a few rays
//! come closer to the Mitsuba reference of the emissive Cornell box. Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::gi::{Bounces, GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The emissive Cornell box (its only light a 0.130 m × 0.105 m ceiling patch).
fn cornell_emissive() -> Scene {
    load_scene_arg(Some(&format!("{ROOT}/assets/scenes/cornell_emissive.toml"))).expect("loads")
}

fn pathtrace(rays: u32, frames: u32, emitter_sampling: bool) -> GiSettings {
    GiSettings {
        method: GiMethod::Pathtrace,
        rays,
        accumulate_frames: frames,
        bounces: Bounces::Fixed(2),
        emitter_sampling,
        ..Default::default()
    }
}

/// The sum of the channels.
fn channels(v: Vec3) -> f32 {
    v.x + v.y + v.z
}

/// The mean radiance (rgb) of an image.
fn mean(img: &HdrImage) -> Vec3 {
    let sum: Vec3 = img.data.iter().map(|p| Vec3::from(*p)).sum();
    sum / img.data.len() as f32
}

/// The light the patch sends directly (one bounce), against Mitsuba's direct-light reference
/// (assets/references/cornell_emissive_direct.exr, an independent estimate of the same
/// integral), as the mean over the pixels that do not show the patch itself (reference radiance
/// below 2 W/(m²·sr); the patch's 30 would otherwise weigh its rasterized outline): the light
/// samples see the exact triangles, the BSDF rays the patch's voxels, whose outline is rounded
/// outward and whose lower faces are nearer than the patch, so they see it larger. Measured at
/// 256², 4 rays × 8 frames: see the message below and docs/measurements/emitter-sampling.md.
/// Noise of the mean: with emitter sampling each of the 65536 pixels averages 32 light samples
/// of the patch, whose relative spread per pixel is below 50% (from the floor, the cosines and
/// distances over the patch vary by less than a factor of 2), so the mean's is below
/// 0.5 / √(65536 · 32) ≈ 0.04%; Mitsuba's reference is converged to about 0.2%. Measured:
/// BSDF rays only +10.7%, with emitter sampling +2.6% (the BSDF rays' MIS-weighted share of
/// the voxels' excess). Bounds: within 4% with emitter sampling (the measured 2.6%, with room
/// for other devices' rounding), and closer than the BSDF rays alone.
#[test]
fn emitter_sampling_matches_the_direct_light_reference() {
    let scene = cornell_emissive();
    let ctx = common::context();
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/cornell_emissive_direct.exr"))
            .expect("reference");
    let keep: Vec<bool> = reference
        .data
        .iter()
        .map(|p| p.iter().all(|&c| c < 2.0))
        .collect();
    let masked_mean = |img: &HdrImage| {
        let (sum, n) = img
            .data
            .iter()
            .zip(&keep)
            .filter(|(_, &k)| k)
            .fold((0.0f64, 0usize), |(s, n), (p, _)| {
                (s + p.iter().map(|&c| f64::from(c)).sum::<f64>(), n + 1)
            });
        sum / n.max(1) as f64
    };
    let want = masked_mean(&reference);
    let mut got = Vec::new();
    for on in [false, true] {
        let settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                bounces: Bounces::Fixed(1),
                ..pathtrace(4, 8, on)
            },
            ..Default::default()
        };
        let img = render_image(&ctx, &scene, &settings).expect("renders").hdr;
        got.push(masked_mean(&img));
    }
    common::assert_no_validation_messages(&ctx);
    let (off, on) = (got[0] / want - 1.0, got[1] / want - 1.0);
    println!(
        "direct light against Mitsuba: BSDF rays only {off:+.4}, with emitter sampling {on:+.4}"
    );
    assert!(on.abs() < 0.04, "with emitter sampling: {on:+.4}");
    assert!(
        on.abs() < off.abs(),
        "BSDF rays only {off:+.4}, with emitter sampling {on:+.4}"
    );
}

/// Converged, the light sample and the BSDF rays estimate the same integral but for the
/// patch's voxelization: the box's mean radiance with and without emitter sampling must agree
/// within their noise and that difference.
///
/// Noise: 64² pixels of 64 rays × 4 frames (256 paths each) of 2 bounces. Without emitter
/// sampling a path finds the patch only when a ray hits its voxels: seen from the floor the
/// patch subtends Ω ≈ A / d² = 0.01365 / 0.548² = 0.045 sr, which a cosine-distributed ray
/// hits with probability about Ω/π = 1.4%, so a pixel's 256 paths see it about 3.7 times and
/// their estimate has a relative standard deviation of about 1/√3.7 = 52%. The image mean
/// averages 4096 such pixels with independent rotations: 52% / √4096 = 0.8%; 4σ = 3.3%. With
/// emitter sampling the noise is far smaller.
///
/// Voxelization: `emitter_sampling_matches_the_direct_light_reference` measures the BSDF
/// rays' direct light 10.7% above Mitsuba's and the light samples' 2.6% above, so the two
/// integrands differ by 8.1% of the direct light away from the patch's own pixels; the direct
/// light is at most the whole mean (and the patch's pixels, the same in both renders, only
/// dilute the difference), so the voxelization moves the ratio by at most 8.1%. Bound: the
/// ratio with / without emitter sampling within 1 − (8.1% + 3.3%) and 1 + 3.3%. Measured
/// 0.960 (0.966 at 256² and 4 rays × 16 frames).
#[test]
fn emitter_sampling_converges_to_the_bsdf_only_mean() {
    let scene = cornell_emissive();
    let ctx = common::context();
    let mut means = Vec::new();
    for on in [false, true] {
        let settings = RenderSettings {
            width: 64,
            height: 64,
            gi: pathtrace(64, 4, on),
            ..Default::default()
        };
        means.push(mean(
            &render_image(&ctx, &scene, &settings).expect("renders").hdr,
        ));
    }
    common::assert_no_validation_messages(&ctx);
    let ratio = channels(means[1]) / channels(means[0]);
    println!(
        "mean radiance: BSDF rays only {:?}, with emitter sampling {:?}, ratio {ratio:.4}",
        means[0], means[1]
    );
    assert!(
        ratio > 1.0 - 0.081 - 0.033 && ratio < 1.0 + 0.033,
        "ratio {ratio:.4}"
    );
}

/// Four rays and one frame at 256² against the Mitsuba full-GI reference
/// (assets/references/cornell_emissive_gi.exr, 2 bounces like the path tracer's default): the
/// issue's target is relMSE 0.1 (BSDF rays only measure 0.18, docs/measurements/
/// emitter-sampling.md), and the light samples must do better than the rays alone.
#[test]
fn emitter_sampling_brings_four_rays_closer_to_the_reference() {
    let scene = cornell_emissive();
    let ctx = common::context();
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/cornell_emissive_gi.exr"))
            .expect("reference");
    let mut rel_mse = Vec::new();
    for on in [false, true] {
        let settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                rays: 4,
                ..pathtrace(4, 1, on)
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        rel_mse.push(
            compare(&reference, &out.hdr, None)
                .expect("same size")
                .rel_mse,
        );
    }
    common::assert_no_validation_messages(&ctx);
    println!(
        "4 rays x 1 frame relMSE: BSDF rays only {:.4}, with emitter sampling {:.4}",
        rel_mse[0], rel_mse[1]
    );
    assert!(
        rel_mse[1] <= 0.1,
        "with emitter sampling: relMSE {}",
        rel_mse[1]
    );
    assert!(rel_mse[1] < rel_mse[0], "relMSE {rel_mse:?}");
}

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

/// The mean radiance (rgb) of an image.
fn mean(img: &HdrImage) -> Vec3 {
    let sum: Vec3 = img.data.iter().map(|p| Vec3::from(*p)).sum();
    sum / img.data.len() as f32
}

/// Converged, the light sample and the BSDF rays estimate the same integral: the box's mean
/// radiance with and without emitter sampling must agree within their noise and the one
/// difference between the two integrands, the emitter's voxelization.
///
/// Noise: 64² pixels of 64 rays × 4 frames (256 paths each) of 2 bounces. Without emitter
/// sampling a path finds the patch only when a ray hits its voxels: seen from the floor the
/// patch subtends Ω ≈ A cosθ / d² = 0.01365 / 0.548² = 0.045 sr, which a cosine-distributed
/// ray hits with probability about Ω/π = 1.4%, so a pixel's 256 paths see it about 3.7 times
/// and their estimate has a relative standard deviation of about 1/√3.7 = 52%. The image mean
/// averages 4096 such pixels with independent rotations: 52% / √4096 = 0.8%; 4σ = 3.3%.
/// With emitter sampling the noise is far smaller.
///
/// Voxelization: the path tracer's rays see the patch as its emission-volume voxels, the
/// light samples see the exact triangles. The default grid's voxel is h = 5.5 mm across the
/// box (0.555 m over 100 voxels at the longest side is at most that); a patch grown by one
/// voxel on every side has (0.130 + 2h)(0.105 + 2h) / (0.130 · 0.105) = 1.19 times its area,
/// an upper bound on the rays' excess (the voxels at its edge are owned by the ceiling or by
/// the patch, whichever covers more of them, so on average the area is nearly the exact one).
/// Only the light the patch sends directly is affected, at most the whole mean. Measured:
/// see the message below and docs/measurements/emitter-sampling.md.
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
    let ratio = means[1] / means[0];
    println!(
        "mean radiance: BSDF rays only {:?}, with emitter sampling {:?}, ratio {ratio:?}",
        means[0], means[1]
    );
    for c in ratio.to_array() {
        assert!((c - 1.0).abs() < BOUND, "ratio {ratio:?}");
    }
}

/// See `emitter_sampling_converges_to_the_bsdf_only_mean`.
const BOUND: f32 = 0.05;

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

//! Transparent surfaces in voxel GI (docs/measurements/transparency.md, "Transparent panes in
//! GI"): the empty Cornell box lit only by a spot aimed at the ceiling, so the floor's light is
//! all indirect, with a horizontal pane between the light and the floor. A pane of opacity 0
//! must block no GI ray; one of opacity 0.5 must pass the light Mitsuba 3's `mask` BSDF
//! passes (assets/references/cornell_pane_gi.exr). The voxel path tracer reads the bits and
//! the albedo volume, both voxelized with stochastic coverage (src/voxel/coverage.rs).
//! Validation on.

mod common;

use std::path::Path;
use voxgi::eval::HdrImage;
use voxgi::gi::{Bounces, GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::Scene;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SIZE: u32 = 128;

fn scene(name: &str) -> Scene {
    Scene::load(Path::new(ROOT).join("assets/scenes").join(name)).expect("scene loads")
}

/// The floor's pixels: the camera (0.273 m high, 0.8 m in front of the box, 39.3° field of
/// view) sees the floor between 11.4° below the axis (its back edge, 1.359 m away) and 18.8°
/// (its front edge), i.e. image rows 0.78–0.98 of the height (tan 11.4° / tan 19.65° = 0.56
/// below the centre), and between the side walls in the middle 58% of the columns at the back.
/// This window keeps inside both with a margin of a few pixels.
fn floor_mean(image: &HdrImage) -> f64 {
    let (w, h) = (image.width, image.height);
    let (mut sum, mut n) = (0.0, 0);
    for y in h * 80 / 100..h * 94 / 100 {
        for x in w * 30 / 100..w * 70 / 100 {
            let p = image.data[(y * w + x) as usize];
            sum += f64::from(p[0] + p[1] + p[2]) / 3.0;
            n += 1;
        }
    }
    sum / f64::from(n)
}

/// The path tracer with every bounce (Russian roulette), as Mitsuba's full-GI reference.
fn render_floor(ctx: &voxgi::vk::Context, name: &str) -> f64 {
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        gi: GiSettings {
            method: GiMethod::Pathtrace,
            rays: 16,
            bounces: Bounces::Unbounded,
            accumulate_frames: 4,
            ..Default::default()
        },
        ..Default::default()
    };
    let out = render_image(ctx, &scene(name), &settings).expect("renders");
    assert!(
        out.hdr
            .data
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)),
        "{name}: finite, non-negative radiance"
    );
    floor_mean(&out.hdr)
}

fn reference_floor(name: &str) -> f64 {
    let r = HdrImage::load(Path::new(ROOT).join("assets/references").join(name)).expect("exr");
    assert_eq!(
        (r.width, r.height),
        (SIZE, SIZE),
        "{name}: rendered at {SIZE}²"
    );
    floor_mean(&r)
}

/// Opacity 0: the pane sets no voxel and no attribute (the bits are those of the box without
/// it, tests/voxelize.rs), and it is invisible in the G-buffer, so the floor's light is that of
/// the box without the pane up to the path tracer's noise, which is the same sequence in both
/// renders. Before stochastic coverage the ratio was 0.032 (the light through the gaps along
/// the walls). The bound is the brief's 5%.
///
/// Opacity 0.5 against Mitsuba's `mask` pane: the bound is the brief's 5% on the ratio
/// pane / no pane, which divides out the path tracer's own error on this lighting (+2.4%
/// without the pane). Mitsuba's references hold 1024 spp over ~1,000 floor pixels (noise far
/// below 1%). Measured on lavapipe: ratio 0.579 against Mitsuba's 0.591 (−2.0%;
/// docs/measurements/transparency.md). One test, so the box without the pane renders once.
#[test]
fn panes_of_opacity_0_and_half_pass_what_mitsubas_mask_passes() {
    let ctx = common::context();
    let without = render_floor(&ctx, "cornell_ceiling_spot.toml");
    let clear = render_floor(&ctx, "cornell_pane_clear.toml");
    let half = render_floor(&ctx, "cornell_pane.toml");
    common::assert_no_validation_messages(&ctx);
    let ref_without = reference_floor("cornell_ceiling_spot_gi.exr");
    let ref_half = reference_floor("cornell_pane_gi.exr");
    let (ratio, ref_ratio) = (half / without, ref_half / ref_without);
    println!(
        "floor: voxgi no pane {without:.5}, clear pane {clear:.5} (ratio {:.4}), half pane \
         {half:.5} (ratio {ratio:.4}); Mitsuba {ref_without:.5}, {ref_half:.5} (ratio \
         {ref_ratio:.4}); half pane / Mitsuba {:.4}",
        clear / without,
        half / ref_half
    );
    assert!(without > 0.0, "the floor gets indirect light");
    assert!(
        (clear / without - 1.0).abs() < 0.05,
        "clear pane ratio {}",
        clear / without
    );
    assert!(
        (ratio / ref_ratio - 1.0).abs() < 0.05,
        "pane ratio {ratio} against Mitsuba's {ref_ratio}"
    );
}

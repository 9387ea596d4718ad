//! voxgi's direct light against Mitsuba 3 direct-only references (assets/references/, see
//! the README there). Thresholds are about twice the values measured when they were set
//! (re-measured after the shadow-acne fix of issue 11, whose before/after is in the last
//! column):
//!
//! | scene | relMSE | FLIP | where the residue is | before the acne fix |
//! |---|---|---|---|---|
//! | cornell | 0.0058 | 0.018 | silhouette and shadow edges (pixel-center shading vs Mitsuba's box-filtered pixels) | 0.0060, 0.021 (acne on the tall block's front face) |
//! | cornell_bunny | 0.0053 | 0.0145 | the same plus the bunny's silhouette and its ears' shadows on its body | 0.0060, 0.015 |
//! | point_light | 0.00093 | 0.0068 | edges; the Phong sphere (Mitsuba has no Phong: exported as a Beckmann blend) | 0.00091, 0.0065 |
//!
//! The tall block's front face alone (`cornell_tall_block_face_is_smooth`): relMSE 3.5e-7,
//! FLIP 0.0025 now; 1.3e-3 and 0.044 with the acne.

mod common;

use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn reference(name: &str, mode: &str) -> HdrImage {
    let path = Path::new(ROOT).join(format!("assets/references/{name}_{mode}.exr"));
    HdrImage::load(&path).unwrap_or_else(|e| panic!("reference {}: {e}", path.display()))
}

fn render(scene: &Scene) -> HdrImage {
    let ctx = common::context();
    let settings = RenderSettings {
        width: 256,
        height: 256,
        ..Default::default()
    };
    let out = render_image(&ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    out.hdr
}

fn check(name: &str, scene_arg: &str, max_rel_mse: f64, max_flip: f64) {
    let scene_arg = if scene_arg.ends_with(".toml") {
        format!("{ROOT}/{scene_arg}")
    } else {
        scene_arg.to_string()
    };
    let scene = load_scene_arg(Some(&scene_arg)).expect("scene loads");
    let img = render(&scene);
    let direct = reference(name, "direct");
    let m = compare(&direct, &img, None).expect("same size");
    println!("{name}: vs direct-only reference: {m:?}");
    assert!(
        m.rel_mse < max_rel_mse,
        "{name}: relMSE {} >= {max_rel_mse}",
        m.rel_mse
    );
    assert!(
        (m.flip_mean as f64) < max_flip,
        "{name}: FLIP {} >= {max_flip}",
        m.flip_mean
    );

    // A deliberate radiometric mistake (a missing 1/pi in the BRDF) must fail the same bounds.
    let wrong = HdrImage {
        data: img
            .data
            .iter()
            .map(|p| p.map(|c| c * std::f32::consts::PI))
            .collect(),
        ..img.clone()
    };
    let w = compare(&direct, &wrong, None).expect("same size");
    assert!(
        w.rel_mse > 10.0 * max_rel_mse && (w.flip_mean as f64) > max_flip,
        "{name}: a missing 1/pi went unnoticed: {w:?}"
    );

    // The baseline every GI method has to beat: direct light against the full-GI reference.
    let gi = compare(&reference(name, "gi"), &img, None).expect("same size");
    println!("{name}: direct-only vs full-GI reference (GI baseline): {gi:?}");
    assert!(
        gi.rel_mse > m.rel_mse,
        "{name}: indirect light must be missing from a direct-only image"
    );
}

#[test]
fn cornell_direct_matches_mitsuba() {
    check("cornell", "cornell", 0.012, 0.036);
}

#[test]
fn cornell_bunny_direct_matches_mitsuba() {
    check(
        "cornell_bunny",
        "assets/scenes/cornell_bunny.toml",
        0.011,
        0.03,
    );
}

#[test]
fn point_light_direct_matches_mitsuba() {
    check(
        "point_light",
        "assets/scenes/point_light.toml",
        0.002,
        0.013,
    );
}

/// The tall block's front face, which the spot light grazes at 87–89° from its normal (the
/// light hangs 12 mm in front of the face's plane, 0.21–0.54 m above its points): the face
/// where shadow acne showed as a moiré of dark dots (issue 11). Pixels inside the face's
/// projected outline, shrunk by 10 % so that no pixel straddles its edges, minus the short
/// block's screen-space box, which hides the face's lower right. Corners in millimeters from
/// Cornell's published measurements, as `assets/scenes/cornell.toml`'s blocks. `true` excludes
/// a pixel, as `compare` wants.
fn tall_face_mask(scene: &Scene, width: u32, height: u32) -> Vec<bool> {
    use glam::{Vec2, Vec3};
    let vp = scene.camera.view_proj(width as f32 / height as f32);
    let screen = |p: Vec3| {
        let c = vp * (p * 1e-3).extend(1.0);
        Vec2::new(
            (c.x / c.w * 0.5 + 0.5) * width as f32,
            (c.y / c.w * 0.5 + 0.5) * height as f32,
        )
    };
    let face = [
        Vec3::new(265.0, 0.0, 296.0),
        Vec3::new(423.0, 0.0, 247.0),
        Vec3::new(423.0, 330.0, 247.0),
        Vec3::new(265.0, 330.0, 296.0),
    ];
    let center = face.iter().copied().sum::<Vec3>() / 4.0;
    let outline: Vec<Vec2> = face
        .iter()
        .map(|&c| screen(center + (c - center) * 0.9))
        .collect();
    let short_block: Vec<Vec2> = [[130.0, 65.0], [82.0, 225.0], [240.0, 272.0], [290.0, 114.0]]
        .iter()
        .flat_map(|&[x, z]| [screen(Vec3::new(x, 0.0, z)), screen(Vec3::new(x, 165.0, z))])
        .collect();
    let (lo, hi) = short_block.iter().fold(
        (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let mut mask = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let sides: Vec<f32> = (0..4)
                .map(|i| (outline[(i + 1) % 4] - outline[i]).perp_dot(p - outline[i]))
                .collect();
            let inside = sides.iter().all(|&s| s > 0.0) || sides.iter().all(|&s| s < 0.0);
            let hidden = p.cmpge(lo).all() && p.cmple(hi).all();
            mask.push(!inside || hidden);
        }
    }
    mask
}

/// The tall block's face against Mitsuba. Bounds: relMSE 5e-5, about twice the reference's own
/// seed-to-seed noise over the whole image (2.7e-5, assets/references/README.md) and 25 times
/// below the acne's 1.3e-3; FLIP 0.01, four times the 0.0025 measured now and a quarter of
/// the acne's 0.044.
#[test]
fn cornell_tall_block_face_is_smooth() {
    let scene = load_scene_arg(Some("cornell")).expect("scene loads");
    let img = render(&scene);
    let mask = tall_face_mask(&scene, img.width, img.height);
    let kept = mask.iter().filter(|&&m| !m).count();
    assert!(kept > 2000, "the face covers only {kept} pixels");
    let m = compare(&reference("cornell", "direct"), &img, Some(&mask)).expect("same size");
    println!("cornell tall block face ({kept} pixels): {m:?}");
    assert!(
        m.rel_mse < 5e-5,
        "tall block face: relMSE {} >= 5e-5",
        m.rel_mse
    );
    assert!(
        (m.flip_mean as f64) < 0.01,
        "tall block face: FLIP {} >= 0.01 (shadow acne?)",
        m.flip_mean
    );
}

//! voxgi's direct light against Mitsuba 3 direct-only references (assets/references/, see
//! the README there). Thresholds are about twice the values measured when they were set:
//!
//! | scene | relMSE | FLIP | where the residue is |
//! |---|---|---|---|
//! | cornell | 0.0060 | 0.021 | silhouette and shadow edges (pixel-center shading vs Mitsuba's box-filtered pixels), acne on the tall block's face that the spot lights almost edge-on |
//! | cornell_bunny | 0.0060 | 0.015 | the same plus the bunny's silhouette |
//! | point_light | 0.0009 | 0.0065 | edges; the Phong sphere (Mitsuba has no Phong: exported as a Beckmann blend) |

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
    check("cornell", "cornell", 0.012, 0.04);
}

#[test]
fn cornell_bunny_direct_matches_mitsuba() {
    check(
        "cornell_bunny",
        "assets/scenes/cornell_bunny.toml",
        0.012,
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

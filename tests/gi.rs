//! Indirect light against the Mitsuba full-GI references: the hemisphere method must beat
//! direct-only rendering on every test scene (relMSE and FLIP), with validation on.

mod common;

use std::path::Path;
use voxgi::eval::{compare, HdrImage, Metrics};
use voxgi::gi::{GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::load_scene_arg;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn metrics(scene_arg: &str, reference: &str, gi: GiSettings) -> Metrics {
    let arg = if scene_arg.ends_with(".toml") {
        format!("{ROOT}/{scene_arg}")
    } else {
        scene_arg.to_string()
    };
    let scene = load_scene_arg(Some(&arg)).expect("scene loads");
    let ctx = common::context();
    let settings = RenderSettings {
        width: 256,
        height: 256,
        gi,
        ..Default::default()
    };
    let out = render_image(&ctx, &scene, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    assert!(
        out.hdr
            .data
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)),
        "finite, non-negative radiance"
    );
    let r = HdrImage::load(Path::new(ROOT).join(format!("assets/references/{reference}_gi.exr")))
        .expect("reference");
    compare(&r, &out.hdr, None).expect("same size")
}

#[test]
fn hemisphere_beats_direct_only_on_every_test_scene() {
    for (scene, reference) in [
        ("cornell", "cornell"),
        ("assets/scenes/cornell_bunny.toml", "cornell_bunny"),
        ("assets/scenes/point_light.toml", "point_light"),
    ] {
        let direct = metrics(scene, reference, GiSettings::default());
        let gi = metrics(
            scene,
            reference,
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 8,
                ..Default::default()
            },
        );
        println!(
            "{reference}: direct relMSE {:.4} FLIP {:.4}; hemisphere relMSE {:.4} FLIP {:.4}",
            direct.rel_mse, direct.flip_mean, gi.rel_mse, gi.flip_mean
        );
        assert!(
            gi.rel_mse < direct.rel_mse,
            "{reference}: hemisphere relMSE {} !< direct {}",
            gi.rel_mse,
            direct.rel_mse
        );
        assert!(
            gi.flip_mean < direct.flip_mean,
            "{reference}: hemisphere FLIP {} !< direct {}",
            gi.flip_mean,
            direct.flip_mean
        );
    }
}

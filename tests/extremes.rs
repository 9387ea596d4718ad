//! Light intensities at the extremes (light intensities from 1e-6 to 1e6 W/sr
//! must give no NaN/Inf in any buffer): radiance is linear in the light, so an image rendered with
//! every light scaled by s, divided by s, must equal the unscaled image, for direct light and for
//! every indirect-light path (light maps, radiance volume, path tracer, VPLs). Likewise a scene scaled
//! from meters to millimeters or kilometers (lights scaled to keep the irradiance) renders the same
//! image. Validation on.

mod common;

use voxgi::gi::{GiMethod, GiSettings, RadianceSource};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, Light, Scene};

fn scaled(scene: &Scene, s: f32) -> Scene {
    let mut scene = scene.clone();
    for light in &mut scene.lights {
        *light = voxgi::scene::scaled(light, s);
    }
    scene
}

/// The HDR image of `scene` with its lights scaled by `s`, divided by `s`.
fn render_per_unit(
    ctx: &voxgi::vk::Context,
    scene: &Scene,
    gi: &GiSettings,
    s: f32,
) -> Vec<[f32; 3]> {
    per_unit(
        render_hdr(ctx, &scaled(scene, s), gi),
        s,
        &format!("{:?}", gi.method),
    )
}

/// `img`, rendered with its light scaled by `s`, divided by `s`; every pixel must be finite
/// and not negative (`what` names the render in the message).
fn per_unit(img: Vec<[f32; 3]>, s: f32, what: &str) -> Vec<[f32; 3]> {
    img.into_iter()
        .map(|p| {
            assert!(
                p.iter().all(|c| c.is_finite() && *c >= 0.0),
                "{what}: light × {s:e}: a pixel is {p:?}"
            );
            p.map(|c| c / s)
        })
        .collect()
}

/// The largest channel value of `img`.
fn peak_of(img: &[[f32; 3]]) -> f32 {
    img.iter().flatten().fold(0.0f32, |a, &b| a.max(b))
}

/// Direct light and every indirect-light path: the light maps, the radiance volume, the
/// path tracer.
fn every_gi_path() -> [(&'static str, GiSettings); 5] {
    [
        ("direct", GiSettings::default()),
        (
            "hemisphere, light maps",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 4,
                ..Default::default()
            },
        ),
        (
            "hemisphere, radiance volume",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 4,
                radiance_source: RadianceSource::Volume,
                ..Default::default()
            },
        ),
        (
            "path tracer",
            GiSettings {
                method: GiMethod::Pathtrace,
                rays: 2,
                bounces: voxgi::gi::Bounces::Fixed(2),
                ..Default::default()
            },
        ),
        (
            "VPLs, 2 bounces",
            GiSettings {
                method: GiMethod::Vpl,
                vpl: voxgi::gi::vpl::VplSettings {
                    per_set: 4,
                    ..Default::default()
                },
                ..Default::default()
            },
        ),
    ]
}

#[test]
fn radiance_scales_linearly_with_light_intensity_from_1e_minus_6_to_1e6() {
    let scene = load_scene_arg(None).expect("the built-in Cornell box");
    let ctx = common::context();
    // ssgi's colour pyramid is f32 and its reflections' colour pre-exposed half floats
    // (scene::pre_exposure); the feedback's clamp is an absolute irradiance, but it clamps
    // the previous frame's light, and this renders a single frame.
    let ssgi = GiSettings {
        method: GiMethod::Ssgi,
        ..Default::default()
    };
    let methods = every_gi_path().into_iter().chain([("ssgi", ssgi)]);
    for (name, gi) in methods {
        let unit = render_per_unit(&ctx, &scene, &gi, 1.0);
        let peak = peak_of(&unit);
        assert!(peak > 0.0, "{name}: the unscaled image is black");
        for s in [1e-6f32, 1e6] {
            let img = render_per_unit(&ctx, &scene, &gi, s);
            // Relative to the image's peak. f32 arithmetic differs by ~1e-7; radiance kept in
            // f16 (light maps and the radiance volume once were) loses ~1.5e-2 at 1e-6 and
            // overflows at 1e6.
            let worst = unit
                .iter()
                .zip(&img)
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
                .fold(0.0f32, f32::max)
                / peak;
            println!("{name}: lights × {s:e}: largest per-unit difference {worst:.2e} of the peak");
            assert!(
                worst < 1e-5,
                "{name}: lights × {s:e} differ from the unscaled image by {worst:.2e} of the peak"
            );
        }
    }
}

/// `scene` scaled by `k` about the origin, with point and spot intensities scaled by k² so that
/// irradiance E = I cosθ / d², and hence every pixel's radiance, stays the same.
fn rescaled(scene: &Scene, k: f32) -> Scene {
    let mut scene = scene.clone();
    for o in &mut scene.objects {
        assert!(o.animation.is_none(), "the test scene is static");
        o.transform.translate *= k;
        o.transform.scale *= k;
    }
    let cam = &mut scene.camera;
    cam.position *= k;
    cam.near *= k;
    cam.far *= k;
    for light in &mut scene.lights {
        match light {
            Light::Point {
                position,
                intensity_w_sr,
            }
            | Light::Spot {
                position,
                intensity_w_sr,
                ..
            } => {
                *position *= k;
                *intensity_w_sr *= k * k;
            }
            Light::Directional { .. } => {}
            other => panic!("the test scene has no area lights: {other:?}"),
        }
    }
    scene
}

#[test]
fn a_millimeter_and_a_kilometer_cornell_box_render_like_the_meter_one() {
    let scene = load_scene_arg(None).expect("the built-in Cornell box");
    let ctx = common::context();
    let methods = every_gi_path();
    for (name, gi) in methods {
        let unit = render_per_unit(&ctx, &scene, &gi, 1.0);
        let mean = |img: &[[f32; 3]]| {
            img.iter()
                .flat_map(|p| p.iter())
                .map(|&c| f64::from(c))
                .sum::<f64>()
                / (img.len() * 3) as f64
        };
        for k in [1e-3f32, 1e3] {
            let img = render_per_unit(&ctx, &rescaled(&scene, k), &gi, 1.0);
            let diff: Vec<f32> = unit
                .iter()
                .zip(&img)
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
                .collect();
            let mean_rel =
                diff.iter().map(|&d| f64::from(d)).sum::<f64>() / diff.len() as f64 / mean(&unit);
            let peak = peak_of(&unit);
            let outliers = diff.iter().filter(|&&d| d > 1e-3 * peak).count();
            println!(
                "{name}: scene × {k:e}: mean difference {mean_rel:.2e} of the mean, {outliers} \
                 channel values off by more than 1e-3 of the peak"
            );
            // Measured: mean 2e-4..8e-4, at most 114 of 12,288 values off (silhouette and
            // shadow-edge pixels whose coverage rounds the other way).
            assert!(
                mean_rel < 3e-3 && outliers < diff.len() / 30,
                "{name}: the Cornell box × {k:e} differs from the meter one: mean {mean_rel:.2e} \
                 of the mean, {outliers} of {} values off by more than 1e-3 of the peak",
                diff.len()
            );
        }
    }
}

/// The HDR pixels of `scene` at 64² with `gi`.
fn render_hdr(ctx: &voxgi::vk::Context, scene: &Scene, gi: &GiSettings) -> Vec<[f32; 3]> {
    let settings = RenderSettings {
        width: 64,
        height: 64,
        gi: *gi,
        ..Default::default()
    };
    let out = render_image(ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(ctx);
    out.hdr.data
}

#[test]
fn a_1e6_a_1e_minus_6_and_a_zero_light_together_add_up() {
    // Radiance is a sum over lights, so the image with lights {A, B, C} equals the image
    // with A alone plus the image with B alone, for C of zero intensity (which must add
    // nothing, not NaN). A = 1e6 W/sr at the ceiling, B = 1e-6 W/sr near the floor (it
    // reaches pixels A's blocks shadow): twelve orders of magnitude in one frame.
    let base = load_scene_arg(Some("cornell-point")).expect("built-in scene");
    let light = |x: f32, y: f32, z: f32, i: f32| Light::Point {
        position: glam::Vec3::new(x, y, z),
        intensity_w_sr: glam::Vec3::splat(i),
    };
    let a = light(0.278, 0.54, 0.28, 1e6);
    let b = light(0.05, 0.05, 0.05, 1e-6);
    let c = light(0.5, 0.3, 0.4, 0.0);
    let with = |lights: Vec<Light>| Scene {
        lights,
        ..base.clone()
    };
    let ctx = common::context();
    let methods = [
        ("direct", GiSettings::default()),
        (
            "hemisphere, light maps",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 4,
                ..Default::default()
            },
        ),
    ];
    for (name, gi) in methods {
        let all = render_hdr(&ctx, &with(vec![a, b, c]), &gi);
        let only_a = render_hdr(&ctx, &with(vec![a]), &gi);
        let only_b = render_hdr(&ctx, &with(vec![b]), &gi);
        assert!(
            only_b.iter().flatten().any(|&v| v > 0.0),
            "{name}: the 1e-6 light lights nothing"
        );
        for (i, ((s, pa), pb)) in all.iter().zip(&only_a).zip(&only_b).enumerate() {
            for ch in 0..3 {
                let want = pa[ch] + pb[ch];
                // Each pixel sums per-light terms in f32: a few ulps (~1e-7) relative, with
                // room for the different summation order; any NaN fails the comparison.
                let ok = (s[ch] - want).abs() <= 1e-5 * want;
                assert!(
                    ok,
                    "{name}: pixel {i} channel {ch}: {} with all three lights, {} + {} = {want} \
                     from A and B alone",
                    s[ch], pa[ch], pb[ch]
                );
            }
        }
    }
}

/// `scene` with every material's emission times `s` (its lights untouched).
fn emission_scaled(scene: &Scene, s: f32) -> Scene {
    let mut scene = scene.clone();
    for m in &mut scene.materials {
        m.emission *= s;
    }
    scene
}

/// What storing a normal number in a half float (IEEE 754 binary16: 11 significant bits) may
/// change it by, relative: 2^-10, one unit in the last place. Round-to-nearest would halve
/// it, but Vulkan lets a conversion to a floating-point format of fewer bits round either to
/// nearest or toward zero (the spec's "Floating-Point Computation" rules), and lavapipe's
/// attachment writes truncate: an emission of 1e-6 pre-exposed to 1.048576 is stored as
/// 1.047852 (−6.9e-4), the value below it, not 1.048828 (+2.4e-4), the nearer.
const HALF_ROUNDOFF: f32 = 1.0 / 1024.0;

#[test]
fn radiance_scales_linearly_with_emission_beyond_half_float_range() {
    // The Cornell box lit only by its emissive ceiling patch (30 W/(m²·sr)), rendered with the
    // emission × s for s = 1e-6/30 and 1e9/30 (emission 1e-6 and 1e9 W/(m²·sr), the range
    // issue #32 asks for: below the half floats' normal range and far above their largest
    // value, 65,504) and divided by s. Half-float images hold
    // radiance pre-exposed by the scene's 2^-k (scene::pre_exposure), a power of two that
    // keeps the scaled values normal: each half-float store then rounds the value to within
    // HALF_ROUNDOFF relative whatever s is, and at s = 1 the emission (30) and what the box
    // sums from it are as rounded. A pixel of positive contributions that went through n
    // stores (the deepest path) differs by at most n HALF_ROUNDOFF relative, plus f32
    // rounding (~1e-6). Without the pre-exposure the 1e6 image lost 15× (65,504 / 3e7 of
    // the emission).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes/cornell_emissive.toml");
    let scene = Scene::load(&path).expect("cornell_emissive loads");
    let emission = 30.0f32;
    let ctx = common::context();
    // Stores on the deepest path of each method's emitted radiance:
    // - direct: the G-buffer's emission attachment (1);
    // - the voxel methods: that, or the voxelizer's per-voxel sum of the fragments' emission
    //   (blended in half float, one rounding per fragment; a few per voxel: 4 at most here)
    //   and the emission volume it is resolved into (1);
    // - ssgi: the G-buffer's emission (1), and the reflections' colour pyramid, whose level
    //   0 and each of its 6 coarser levels (64² down to 1²) round once (7).
    // - VPLs: the emission volume as for the voxel methods (5), whose voxels become the
    //   emitting VPLs; the VPL buffer and the gather are f32.
    let methods: [(&str, GiSettings, f32); 6] = [
        ("direct", GiSettings::default(), 1.0),
        (
            "hemisphere, light maps",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 4,
                ..Default::default()
            },
            5.0,
        ),
        (
            "hemisphere, radiance volume",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 4,
                radiance_source: RadianceSource::Volume,
                ..Default::default()
            },
            5.0,
        ),
        (
            "path tracer",
            GiSettings {
                method: GiMethod::Pathtrace,
                rays: 2,
                bounces: voxgi::gi::Bounces::Fixed(2),
                ..Default::default()
            },
            5.0,
        ),
        (
            "vpl",
            GiSettings {
                method: GiMethod::Vpl,
                ..Default::default()
            },
            5.0,
        ),
        (
            "ssgi",
            GiSettings {
                method: GiMethod::Ssgi,
                ..Default::default()
            },
            8.0,
        ),
    ];
    for (name, gi, stores) in methods {
        let unit = render_hdr(&ctx, &scene, &gi);
        let peak = peak_of(&unit);
        assert_eq!(
            peak, emission,
            "{name}: the emitter reads {peak}, not its emission"
        );
        let bound = stores * HALF_ROUNDOFF + 1e-5;
        for s in [1e-6f32 / emission, 1e9 / emission] {
            let img = render_hdr(&ctx, &emission_scaled(&scene, s), &gi);
            // The visible emitter reads its emission (the largest pixel: the box has no other
            // light, and nothing it reflects is brighter than its source).
            let scaled_peak = peak_of(&img);
            let want = emission * s;
            assert!(
                (scaled_peak - want).abs() <= HALF_ROUNDOFF * want,
                "{name}: emission × {s:e}: the emitter reads {scaled_peak}, not {want}"
            );
            let img = per_unit(img, s, name);
            // Per pixel, relative to the pixel: the indirect light is ~1e-4 of the emitter,
            // which an error relative to the peak would not see. Pixels below 1e-6 of the
            // peak (f32's resolution of the emitter's own pixels) are compared absolutely.
            let mut worst = 0.0f32;
            for (a, b) in unit.iter().zip(&img) {
                for c in 0..3 {
                    worst = worst.max((a[c] - b[c]).abs() / a[c].max(1e-6 * peak));
                }
            }
            println!(
                "{name}: emission × {s:e}: largest per-unit difference {worst:.2e} of the pixel \
                 (bound {bound:.2e})"
            );
            assert!(
                worst <= bound,
                "{name}: emission × {s:e} differs from the unscaled image by {worst:.2e} of a \
                 pixel (bound {bound:.2e})"
            );
        }
    }
}

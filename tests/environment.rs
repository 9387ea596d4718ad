//! The `[environment]` table: the background seen by camera rays that miss, and the light GI
//! rays bring back when they leave the voxel grid. Closed forms: a Lambert floor under a
//! constant sky, the equirectangular map's axes (Mitsuba 3's `envmap` convention) on the
//! background, and the sky-lit courtyard against its Mitsuba reference. Validation on.

mod common;

use glam::Vec3;
use std::path::{Path, PathBuf};
use voxgi::eval::{compare, HdrImage};
use voxgi::gi::{Bounces, GiMethod, GiSettings, RadianceSource};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{Environment, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SIZE: u32 = 32;
const SKY: [f32; 3] = [0.8, 1.0, 1.2];
const FLOOR_ALBEDO: f32 = 0.5;

/// A 4 m Lambert floor at y = 0, nothing else, seen from above at an angle so that the upper
/// rows of the image show the sky; `environment` is the scene's `[environment]` table (empty:
/// none).
fn floor_scene(environment: &str) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [0.0, 1.0, -1.5]
target = [0.0, 0.6, 0.0]
fov_y_deg = 60.0
[[objects]]
builtin = "quad"
scale = [4.0, 1.0, 4.0]
material = {{ albedo = {FLOOR_ALBEDO} }}
{environment}
"#
    );
    Scene::from_toml_str(&toml, Path::new("<floor scene>"), Path::new(ROOT)).expect("parses")
}

fn constant_sky() -> String {
    format!(
        "[environment]\nkind = \"constant\"\nradiance = [{}, {}, {}]",
        SKY[0], SKY[1], SKY[2]
    )
}

fn render(ctx: &common::TestContext, scene: &Scene, gi: GiSettings) -> HdrImage {
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        gi,
        ..Default::default()
    };
    render_image(ctx, scene, &settings).expect("renders").hdr
}

fn pixel(img: &HdrImage, x: u32, y: u32) -> Vec3 {
    Vec3::from(img.data[(y * img.width + x) as usize])
}

/// The GI settings measured: the path tracer (2 bounces), the hemisphere method with light
/// maps, and with the direct-radiance volume.
fn methods() -> [GiSettings; 3] {
    let hemisphere = GiSettings {
        method: GiMethod::Hemisphere,
        rays: 16,
        ..Default::default()
    };
    [
        GiSettings {
            method: GiMethod::Pathtrace,
            rays: 16,
            bounces: Bounces::Fixed(2),
            ..Default::default()
        },
        hemisphere,
        GiSettings {
            radiance_source: RadianceSource::Volume,
            ..hemisphere
        },
    ]
}

/// A Lambert floor (albedo ρ) under a constant sky of radiance L with nothing above it: every
/// direction of its upper hemisphere sees the sky, so E = ∫ L cos θ dω = π L and the outgoing
/// radiance is ρ/π · π L = ρ L (the furnace-like closed form; the floor is flat, so nothing
/// reflects back onto it). Every GI ray from the floor goes up and leaves the grid, so each
/// sample is exactly L: the estimate has no variance, and the bound is float rounding (1e-3).
/// The sky pixels (the upper rows) show L itself, and without the table they are black and
/// the floor gets no light, as before the table existed.
#[test]
fn floor_under_a_constant_sky_reflects_rho_times_l() {
    let ctx = common::context();
    let lit = floor_scene(&constant_sky());
    let dark = floor_scene("");
    let sky = Vec3::from(SKY);
    for gi in methods() {
        let img = render(&ctx, &lit, gi);
        let floor = pixel(&img, SIZE / 2, SIZE - 2);
        let background = pixel(&img, SIZE / 2, 1);
        println!(
            "{:?} {:?}: floor {floor}, sky {background}",
            gi.method, gi.radiance_source
        );
        let expected = FLOOR_ALBEDO * sky;
        assert!(
            (floor - expected).abs().max_element() < 1e-3 * expected.max_element(),
            "{:?}: floor {floor}, expected ρL = {expected}",
            gi.method
        );
        assert!(
            (background - sky).abs().max_element() < 1e-5,
            "{:?}: sky pixel {background}, expected L = {sky}",
            gi.method
        );
        let none = render(&ctx, &dark, gi);
        assert_eq!(pixel(&none, SIZE / 2, 1), Vec3::ZERO);
        assert_eq!(pixel(&none, SIZE / 2, SIZE - 2), Vec3::ZERO);
    }
    common::assert_no_validation_messages(&ctx);
}

/// A 16 × 8 map whose columns hold four colors in blocks two texels wide, centred on
/// u = 0 (red), 1/4 (green), 1/2 (blue) and 3/4 (white), grey elsewhere, the same in every
/// row; written as OpenEXR into `dir`.
fn quadrant_map(dir: &Path) -> PathBuf {
    let (w, h) = (16u32, 8u32);
    let color = |x: u32| match x {
        15 | 0 => [1.0, 0.0, 0.0],
        3 | 4 => [0.0, 1.0, 0.0],
        7 | 8 => [0.0, 0.0, 1.0],
        11 | 12 => [1.0, 1.0, 1.0],
        _ => [0.2, 0.2, 0.2],
    };
    let data: Vec<f32> = (0..w * h).flat_map(|i| color(i % w)).collect();
    let path = dir.join("quadrants.exr");
    image::Rgb32FImage::from_raw(w, h, data)
        .expect("sizes agree")
        .save_with_format(&path, image::ImageFormat::OpenExr)
        .expect("writes the map");
    path
}

/// The background along the horizon follows Mitsuba's `envmap` axes: u = atan2(x, −z) / 2π,
/// so looking along +X the camera sees u = 1/4 and along +Z u = 1/2; `rotation_deg = 90`
/// turns the map counter-clockwise seen from above, carrying its u = 0 column (−Z) to −X. The
/// camera's centre pixels look within a degree of the axis, where bilinear filtering of the
/// two-texel blocks returns the block's color exactly (a texel is 22.5° wide).
#[test]
fn map_background_follows_mitsubas_envmap_axes() {
    let dir = std::env::temp_dir().join(format!("voxgi-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let map = quadrant_map(&dir);
    let ctx = common::context();
    let cases = [
        ([1.0, 0.0, 0.0], 0.0, [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 1.0], 0.0, [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], 0.0, [1.0, 1.0, 1.0]),
        ([0.0, 0.0, -1.0], 0.0, [1.0, 0.0, 0.0]),
        ([-1.0, 0.0, 0.0], 90.0, [1.0, 0.0, 0.0]),
        ([0.0, 0.0, -1.0], 90.0, [0.0, 1.0, 0.0]),
    ];
    for (forward, rotation, expected) in cases {
        let f = Vec3::from(forward);
        // Something to draw (a scene has an object), well behind the camera.
        let behind = -f * 10.0;
        let toml = format!(
            r#"
[camera]
position = [0.0, 0.0, 0.0]
forward = [{}, {}, {}]
fov_y_deg = 10.0
[[objects]]
builtin = "cube"
translate = [{}, {}, {}]
[environment]
kind = "map"
file = "{}"
rotation_deg = {rotation}
scale = 2.0
"#,
            f.x,
            f.y,
            f.z,
            behind.x,
            behind.y,
            behind.z,
            map.display()
        );
        let scene =
            Scene::from_toml_str(&toml, Path::new("<map scene>"), Path::new(ROOT)).expect("parses");
        let img = render(&ctx, &scene, GiSettings::default());
        let seen = pixel(&img, SIZE / 2, SIZE / 2);
        let want = Vec3::from(expected) * 2.0;
        // The CPU twin (nearest texel) agrees on the axis.
        let cpu = scene.environment.as_ref().expect("map").radiance_toward(f);
        println!("forward {f}, rotation {rotation}: {seen} (CPU {cpu})");
        assert!(
            (seen - want).abs().max_element() < 1e-4,
            "looking along {f} with rotation {rotation}°: {seen}, expected {want}"
        );
        assert!((cpu - want).abs().max_element() < 1e-6, "CPU twin {cpu}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    common::assert_no_validation_messages(&ctx);
}

/// `img` box-filtered to half its width and height (a 2 × 2 mean: a pixel of the half-size
/// image is the mean radiance over its area, as the reference's box filter makes it).
fn box_half(img: &HdrImage) -> HdrImage {
    let (w, h) = (img.width / 2, img.height / 2);
    let data = (0..w * h)
        .map(|i| {
            let (x, y) = (2 * (i % w), 2 * (i / w));
            let sum = pixel(img, x, y)
                + pixel(img, x + 1, y)
                + pixel(img, x, y + 1)
                + pixel(img, x + 1, y + 1);
            (sum * 0.25).to_array()
        })
        .collect();
    HdrImage::new(w, h, data).expect("sizes agree")
}

/// The sky-lit courtyard (`assets/scenes/sky_courtyard.toml`: an equirectangular sky map, no
/// lights) against its Mitsuba 3 full-GI reference (`assets/references/sky_courtyard_gi.exr`,
/// 256², 2048 spp, made by `tools/reference`; docs/measurements/environment.md has the
/// numbers at 256²). Here at 128² (the reference box-filtered 2 × 2 to match) with the path
/// tracer's unbounded paths (16 rays × 4 frames) and the hemisphere method (64 rays). The
/// bounds are the issue's targets, 0.02 for the path tracer and 0.05 for the hemisphere
/// method; measured on lavapipe: 0.0020 and 0.0386 (0.0050 and 0.0415 while the map was read
/// through an anisotropic sampler, docs/design/environment.md; the hemisphere's error is its missing
/// second bounce of sky light, a bias, not noise; the reference's own noise is about 1e-4).
#[test]
fn sky_courtyard_matches_its_mitsuba_reference() {
    let scene = Scene::load(Path::new(ROOT).join("assets/scenes/sky_courtyard.toml"))
        .expect("loads the courtyard");
    assert!(matches!(scene.environment, Some(Environment::Map(_))));
    let reference = box_half(
        &HdrImage::load(Path::new(ROOT).join("assets/references/sky_courtyard_gi.exr"))
            .expect("reads the reference"),
    );
    let ctx = common::context();
    let size = reference.width;
    let cases = [
        (
            GiSettings {
                method: GiMethod::Pathtrace,
                rays: 16,
                bounces: Bounces::Unbounded,
                accumulate_frames: 4,
                ..Default::default()
            },
            0.02,
        ),
        (
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 64,
                ..Default::default()
            },
            0.05,
        ),
    ];
    for (gi, bound) in cases {
        let settings = RenderSettings {
            width: size,
            height: size,
            gi,
            ..Default::default()
        };
        let img = render_image(&ctx, &scene, &settings).expect("renders").hdr;
        let m = compare(&reference, &img, None).expect("same size");
        println!("{:?}: relMSE {:.4}", gi.method, m.rel_mse);
        assert!(
            m.rel_mse < bound,
            "{:?}: relMSE {} >= {bound}",
            gi.method,
            m.rel_mse
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// The courtyard under the analytic sky (`assets/scenes/sky_courtyard_sunsky.toml`:
/// Hosek–Wilkie, turbidity 3, its sun the directional light 44.6° up in the south-west)
/// against Mitsuba 3's `sunsky` emitter (`sun_scale` 0) plus a `directional` emitter, full GI
/// (`assets/references/sky_courtyard_sunsky_gi.exr`, 128², 1024 spp, max_depth 64): Mitsuba
/// evaluates the sky itself, so this checks voxgi's model, its bake into the map and the
/// export together. Path tracer, unbounded, 16 rays × 4 frames. The bound is the issue's target
/// for a sky-lit scene's path tracer, 0.02; measured on lavapipe: relMSE 0.0019, mean 0.983,
/// 0.978, 0.971 of Mitsuba's (docs/measurements/environment.md), so a tenfold margin for the
/// path tracer's noise at 64 paths per pixel and the reference's at 1024 spp.
#[test]
fn sunsky_courtyard_matches_its_mitsuba_reference() {
    let scene = Scene::load(Path::new(ROOT).join("assets/scenes/sky_courtyard_sunsky.toml"))
        .expect("loads the courtyard");
    assert!(matches!(scene.environment, Some(Environment::Sky { .. })));
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/sky_courtyard_sunsky_gi.exr"))
            .expect("reads the reference");
    let ctx = common::context();
    // 4 rays × 4 frames (16 paths per pixel): relMSE 0.0015 measured (0.0020 with the
    // anisotropic sampler the map had before), against 0.0019 at
    // 16 × 4, which took most of the suite's 414 s in this file. The error is the voxel
    // bias, not noise, so a quarter of the paths costs nothing against the bound, and the test
    // takes about a minute under load.
    let gi = GiSettings {
        method: GiMethod::Pathtrace,
        rays: 4,
        bounces: Bounces::Unbounded,
        accumulate_frames: 4,
        ..Default::default()
    };
    let settings = RenderSettings {
        width: reference.width,
        height: reference.height,
        gi,
        ..Default::default()
    };
    let img = render_image(&ctx, &scene, &settings).expect("renders").hdr;
    let m = compare(&reference, &img, None).expect("same size");
    println!(
        "sunsky courtyard, path tracer 4 × 4: relMSE {:.4}",
        m.rel_mse
    );
    const BOUND: f64 = 0.02;
    assert!(m.rel_mse < BOUND, "relMSE {} >= {BOUND}", m.rel_mse);
    common::assert_no_validation_messages(&ctx);
}

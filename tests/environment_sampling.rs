//! Importance sampling of the environment map (`gi.env_sampling`,
//! `glsl/include/environment_sampling.glsl`): a white-ish Lambert floor under a map black but
//! for a 2 × 2-texel sun converges to the closed-form irradiance, in the direct light
//! (`direct_emitters`, under `--gi none`) and in the path tracer's next-event estimation; and a
//! map with a glow too faint to be sampled (its share α of map samples is 0) renders as
//! without importance sampling and converges to its closed form. `tools/envis_twin.py` is the numpy
//! oracle of the same estimator (its numbers are quoted below). Validation on.

mod common;

use glam::Vec3;
use std::path::{Path, PathBuf};
use voxgi::gi::{Bounces, GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::environment::{equirect_direction, EnvironmentCdf};
use voxgi::scene::{Scene, ShadowSettings};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SIZE: u32 = 64;
const ALBEDO: f32 = 0.5;
const ROTATION_DEG: f32 = 30.0;
const MAP_W: u32 = 64;
const MAP_H: u32 = 32;
/// The sun: texels x 40-41, rows 9-10 (about 30° above the horizon), radiance 1000.
const SUN: (u32, u32, f32) = (40, 9, 1000.0);

/// The sun map's texel (grey: the same in every channel).
fn sun_texel(x: u32, y: u32) -> f32 {
    let (sx, sy, l) = SUN;
    if (sx..sx + 2).contains(&x) && (sy..sy + 2).contains(&y) {
        l
    } else {
        0.0
    }
}

fn write_map(dir: &Path, name: &str, texel: impl Fn(u32, u32) -> f32) -> PathBuf {
    let data: Vec<f32> = (0..MAP_W * MAP_H)
        .flat_map(|i| [texel(i % MAP_W, i / MAP_W); 3])
        .collect();
    let path = dir.join(name);
    image::Rgb32FImage::from_raw(MAP_W, MAP_H, data)
        .expect("sizes agree")
        .save_with_format(&path, image::ImageFormat::OpenExr)
        .expect("writes the map");
    path
}

/// An 8 m Lambert floor at y = 0 seen from 1.5 m above, looking nearly straight down, so
/// every pixel is floor, under the map `file` turned by ROTATION_DEG.
fn floor_scene(file: &Path) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [0.0, 1.5, 0.0]
target = [0.0, 0.0, 0.3]
fov_y_deg = 50.0
[[objects]]
builtin = "quad"
scale = [8.0, 1.0, 8.0]
material = {{ albedo = {ALBEDO} }}
[environment]
kind = "map"
file = "{}"
rotation_deg = {ROTATION_DEG}
"#,
        file.display()
    );
    Scene::from_toml_str(&toml, Path::new("<floor scene>"), Path::new(ROOT)).expect("parses")
}

/// The bilinear lookup of `environment_radiance` (repeating in u, v within the first and last
/// rows' centres) of a grey map, at map coordinates (u, v).
fn bilinear(texel: &impl Fn(u32, u32) -> f32, u: f64, v: f64) -> f64 {
    let (w, h) = (f64::from(MAP_W), f64::from(MAP_H));
    let v = v.clamp(0.5 / h, 1.0 - 0.5 / h);
    let (x, y) = (u * w - 0.5, v * h - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let xi = |k: f64| (k.rem_euclid(w)) as u32;
    let yi = |k: f64| (k.clamp(0.0, h - 1.0)) as u32;
    let t = |a: f64, b: f64| f64::from(texel(xi(a), yi(b)));
    let top = t(x0, y0) * (1.0 - fx) + t(x0 + 1.0, y0) * fx;
    let bottom = t(x0, y0 + 1.0) * (1.0 - fx) + t(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The irradiance of an upward-facing surface, E = ∫ L cos θ dω over the upper hemisphere,
/// by the midpoint rule over 16 × 16 sub-texels of the bilinear lookup (dω = 2π² sin θ du dv);
/// the same lookup under the same rotation as the shaders', so only the sampling differs.
/// The rule's error on the piecewise-bilinear integrand is far below the tests' bounds (the
/// twin's quadrature at 8 × 8 agrees with π L for a constant to 3e-5).
fn irradiance(texel: impl Fn(u32, u32) -> f32) -> f64 {
    let sub = 16;
    let (nu, nv) = (MAP_W * sub, MAP_H * sub / 2);
    let rotation = ROTATION_DEG.to_radians();
    let mut e = 0.0;
    for j in 0..nv {
        let v = (f64::from(j) + 0.5) / f64::from(MAP_H * sub);
        let dw = 2.0 * std::f64::consts::PI.powi(2) * (std::f64::consts::PI * v).sin()
            / f64::from(nu * MAP_H * sub);
        for i in 0..nu {
            let u = (f64::from(i) + 0.5) / f64::from(nu);
            // The map coordinate of the world direction (u, v) under the rotation is (u, v)
            // itself: the lookup turns the direction back.
            let d = equirect_direction(u as f32, v as f32, rotation);
            e += bilinear(&texel, u, v) * f64::from(d.y.max(0.0)) * dw;
        }
    }
    e
}

/// Renders with `gi`; under `--gi none` the direct light takes `gi.rays` samples per pixel
/// (`shadow.direct_samples`, which `direct` below means by its count).
fn render(ctx: &common::TestContext, scene: &Scene, gi: GiSettings) -> Vec<Vec3> {
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        shadow: ShadowSettings {
            direct_samples: gi.rays,
            ..Default::default()
        },
        gi,
        ..Default::default()
    };
    let img = render_image(ctx, scene, &settings).expect("renders").hdr;
    img.data.iter().map(|&p| Vec3::from(p)).collect()
}

fn mean(pixels: &[Vec3]) -> Vec3 {
    pixels.iter().copied().sum::<Vec3>() / pixels.len() as f32
}

fn direct(rays: u32, env_sampling: bool) -> GiSettings {
    GiSettings {
        method: GiMethod::None,
        rays,
        env_sampling,
        ..Default::default()
    }
}

/// Under the sun map the floor's radiance is ρ/π E with E the quadrature above. The direct
/// light at K = 16 (8 map samples and 8 cosine samples per pixel, balance heuristic), and the
/// path tracer at 16 paths of one bounce (each vertex one map sample and one cosine ray), both
/// average 64² = 4096 pixels. The twin's relative standard deviation of one such pair is 0.73
/// (cosine alone: 11), so the mean's is 0.73 / sqrt(8 · 4096) = 0.004 for the direct light and
/// 0.73 / sqrt(16 · 4096) = 0.003 for the path tracer: the bound 0.03 is more than 7 standard
/// deviations, and the GPU bias once seen here (1.7 to 3 times E) is far outside it. Pixels
/// are rotated sample sets, not independent draws, so the bound is loose on purpose.
#[test]
fn floor_under_a_sun_map_converges_to_the_closed_form() {
    let dir = common::temp_dir("envis-sun");
    let scene = floor_scene(&write_map(&dir, "sun.exr", sun_texel));
    // Nearly all of the power lies in the sun's 4 texels: the map is sampled.
    assert_eq!(
        map_share(&scene),
        voxgi::scene::environment::MAP_SHARE_MAX as f32
    );
    let expected = f64::from(ALBEDO) / std::f64::consts::PI * irradiance(sun_texel);
    let ctx = common::context();
    let path_tracer = GiSettings {
        method: GiMethod::Pathtrace,
        rays: 16,
        bounces: Bounces::Fixed(1),
        env_sampling: true,
        ..Default::default()
    };
    for (name, gi) in [
        ("direct light", direct(16, true)),
        ("path tracer", path_tracer),
    ] {
        let m = mean(&render(&ctx, &scene, gi));
        let ratio = f64::from(m.x) / expected;
        println!("{name}: floor mean {m}, closed form {expected:.5}, ratio {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.03, "{name}: {ratio}");
    }
    common::assert_no_validation_messages(&ctx);
    std::fs::remove_dir_all(&dir).ok();
}

/// The map's share α of importance samples (`EnvironmentCdf::map_share`) of `scene`'s map.
fn map_share(scene: &Scene) -> f32 {
    scene
        .environment
        .as_ref()
        .and_then(|e| e.map())
        .and_then(EnvironmentCdf::new)
        .map_or(0.0, |cdf| cdf.map_share)
}

/// A sky of 1 with a 4 × 4-texel glow of 20 (rows 8-11, 22° to 45° above the horizon): its
/// brightest 1% of the sphere holds 15% of the power (the twin), short of the majority that
/// makes a map worth sampling, so α = 0 and the default (importance sampling on) renders
/// exactly what cosine samples alone render. Both converge to ρ/π E, E the quadrature above:
/// the twin's relative standard deviation of one K = 16 cosine estimate is 0.446, so at
/// K = 64 about 0.22 and the mean of 4096 pixels 0.0035: the bound 0.025 is seven of them.
#[test]
fn glow_map_keeps_the_cosine_samples_and_converges() {
    let glow = |x: u32, y: u32| {
        if (20..24).contains(&x) && (8..12).contains(&y) {
            20.0
        } else {
            1.0
        }
    };
    let dir = common::temp_dir("envis-glow");
    let scene = floor_scene(&write_map(&dir, "glow.exr", glow));
    assert_eq!(map_share(&scene), 0.0);
    let expected = f64::from(ALBEDO) / std::f64::consts::PI * irradiance(glow);
    let ctx = common::context();
    let off = render(&ctx, &scene, direct(64, false));
    let on = render(&ctx, &scene, direct(64, true));
    assert!(off == on, "α = 0 renders as without importance sampling");
    let m = mean(&on);
    let ratio = f64::from(m.x) / expected;
    println!("floor mean {m}, closed form {expected:.5}, ratio {ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.025, "{ratio}");
    common::assert_no_validation_messages(&ctx);
    std::fs::remove_dir_all(&dir).ok();
}

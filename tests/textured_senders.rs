//! Texture maps on the senders of indirect light (docs/design/materials.md): an albedo
//! texture (`map_Kd`) in the reflective light maps (hemisphere method, VPLs) and in the albedo
//! volume (path tracer), and an emission map (`map_Ke`) at the points the VPL emitter rays
//! start from, each against the closed-form integral over the texture. Validation is on; any
//! message fails.

mod common;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use voxgi::eval::HdrImage;
use voxgi::gi::{Bounces, GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{Scene, TextureData, VplSettings, VplVisibility};
use voxgi::voxel::maps::sample_map_cpu;

const PI: f32 = std::f32::consts::PI;

/// A fresh directory for one test's scene files.
fn scene_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An 8 × 1 sRGB texture whose texels 0..4 have code `left` and 4..8 code `right`, written as
/// `name` in `dir`.
fn halves_png(dir: &Path, name: &str, left: [u8; 3], right: [u8; 3]) {
    image::RgbImage::from_fn(8, 1, |x, _| image::Rgb(if x < 4 { left } else { right }))
        .save(dir.join(name))
        .unwrap();
}

/// The scene's texture named `name` (its file stem).
fn texture<'a>(s: &'a Scene, name: &str) -> &'a TextureData {
    s.textures
        .iter()
        .find(|t| t.path.file_stem().is_some_and(|f| f == name))
        .expect("the texture is loaded")
}

/// The mean indirect radiance (render minus `direct`) over the 8 × 8 pixels around `centre`.
fn window_mean(img: &HdrImage, direct: &HdrImage, centre: (u32, u32), size: u32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for y in centre.1 - 4..centre.1 + 4 {
        for x in centre.0 - 4..centre.0 + 4 {
            let i = (y * size + x) as usize;
            sum += Vec3::from(img.data[i]) - Vec3::from(direct.data[i]);
        }
    }
    sum / 64.0
}

/// A Lambert floor y = 0 (x, z in [−2, 2], u = (x + 2)/4) whose `map_Kd` is red on x < 0 and
/// green on x > 0 ([`RED`], [`GREEN`]; `Kd` their mean, what the light maps and the volume
/// took before), lit by a directional light (irradiance E⊥ = π W/m² from 45°, toward +z),
/// beside a white wall (ρ 0.8) at z = 1 facing the camera. With `textured` false the floor
/// has `Kd` alone.
fn halves_scene(textured: bool) -> (Scene, PathBuf) {
    let dir = scene_dir(&format!("halves_{textured}"));
    halves_png(&dir, "halves.png", RED, GREEN);
    let map = if textured { "map_Kd halves.png\n" } else { "" };
    let mean = |c: usize| (decode(RED[c]) + decode(GREEN[c])) / 2.0;
    std::fs::write(
        dir.join("floor.mtl"),
        format!(
            "newmtl floor\nKd {} {} {}\n{map}",
            mean(0),
            mean(1),
            mean(2)
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("floor.obj"),
        "mtllib floor.mtl\nusemtl floor\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\nf 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n",
    )
    .unwrap();
    let toml = dir.join("scene.toml");
    std::fs::write(
        &toml,
        r#"
[camera]
position = [0.0, 0.6, -1.0]
target = [0.0, 0.6, 1.0]
fov_y_deg = 60.0
near = 0.01
far = 20.0
[[lights]]
kind = "directional"
direction = [0.0, -0.70710678, 0.70710678]
irradiance_w_m2 = 3.14159265
[[objects]]
name = "floor"
mesh = "floor.obj"
[[objects]]
builtin = "quad"
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 1.5, 1.0]
scale = [4.0, 1.0, 4.0]
material = { albedo = [0.8, 0.8, 0.8] }
"#,
    )
    .unwrap();
    (Scene::load(&toml).expect("the halves scene loads"), dir)
}

/// sRGB codes of the floor texture's halves (linear 0.80, 0.02, 0.02 and 0.02, 0.80, 0.02).
const RED: [u8; 3] = [231, 38, 38];
const GREEN: [u8; 3] = [38, 231, 38];

fn decode(c: u8) -> f32 {
    voxgi::eval::srgb_decode(f32::from(c) / 255.0)
}

/// The irradiance at wall point `p` (on z = 1, normal −z) from the floor in front of the wall
/// (x in [−2, 2], z in [−2, 1]) under the irradiance `e_floor`, whose albedo at x is
/// `albedo(x)`: E(p) = ∫ ρ(x)/π E_floor cos θ_x cos θ_p / d² dA (each floor point sends the
/// radiance ρ/π E_floor toward p, seen under the solid angle cos θ_x dA / d²), by the midpoint
/// rule on 1 cm cells.
fn floor_to_wall(p: Vec3, e_floor: f32, albedo: &dyn Fn(f32) -> Vec3) -> Vec3 {
    let cell = 0.01f32;
    let mut sum = Vec3::ZERO;
    for i in 0..400 {
        let x = -2.0 + (i as f32 + 0.5) * cell;
        let rho = albedo(x);
        for k in 0..300 {
            let q = Vec3::new(x, 0.0, -2.0 + (k as f32 + 0.5) * cell);
            let to_p = p - q;
            let d2 = to_p.length_squared();
            let w = to_p / d2.sqrt();
            let (cos_x, cos_p) = (w.y, w.z);
            if cos_x <= 0.0 || cos_p <= 0.0 {
                continue;
            }
            sum += rho / PI * (e_floor * cos_x * cos_p / d2);
        }
    }
    sum * (cell * cell)
}

/// An albedo texture on a sender, through every method: the floor of [`halves_scene`] reflects
/// red light onto the wall's left and green onto its right. The wall's indirect radiance (the
/// render minus direct light only) in two 8 × 8 windows, at x ≈ ∓0.7 m, against
/// ρ_wall/π · [`floor_to_wall`] with the floor's albedo the texture as the G-buffer's sampler
/// reads it (bilinear, level 0: the CPU twin `sample_map_cpu`, the halves' linear values with
/// a ramp half a texel wide around each border), for the hemisphere method and the VPLs (the
/// light maps' texels sample the texture) and the path tracer (the albedo volume's voxels
/// average it), each with one bounce. The same integral with the floor's `Kd` (the halves'
/// mean, what both took before) differs by far more than the bound in both windows (asserted
/// below: more than 3 × the bound), so the test tells the texture from the mean.
///
/// Bound 4% (the GGX senders' 3% in `tests/gi.rs`, widened by a point: the hemisphere's 256
/// cosine rays per pixel and the VPLs' 16 × 256 point senders are quadratures of the same
/// integral, and here a tenth of the windows' light is the dim half's, so its relative error
/// weighs more; the path tracer's 4 × 64 paths per pixel, 64 pixels, leave a relative standard
/// error about 0.5%, and its voxel hits sit up to half a voxel, 1.6 cm, off the floor).
/// Measured on lavapipe: hemisphere 1.5% / 1.6%, VPLs 0.7% / 2.7%, path tracer 2.1% / 1.8%
/// (worst channel per window); the mean `Kd` is 324% off in both windows.
#[test]
fn an_albedo_texture_on_a_sender_matches_the_integral_over_its_halves() {
    let (scene, dir) = halves_scene(true);
    let t = texture(&scene, "halves");
    // The floor's texture coordinate at x is u = (x + 2)/4 (any v: the texture is one row).
    let textured = |x: f32| sample_map_cpu(t, Vec2::new((x + 2.0) / 4.0, 0.5), -64.0).truncate();
    let kd = scene.materials[scene.objects[0].materials[0]].albedo;
    let flat = |_: f32| kd;
    let e_floor = PI * std::f32::consts::FRAC_1_SQRT_2;
    let ctx = common::context();
    let size = 64u32;
    let render = |gi: GiSettings| {
        let settings = RenderSettings {
            width: size,
            height: size,
            gi,
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        out.hdr
    };
    let direct = render(GiSettings::default());
    let centres = [(12u32, 40u32), (52, 40)];
    let bound = 0.04;
    let expected: Vec<(Vec3, Vec3)> = centres
        .iter()
        .map(|&(cx, cy)| {
            let (mut tex, mut mean) = (Vec3::ZERO, Vec3::ZERO);
            for y in cy - 4..cy + 4 {
                for x in cx - 4..cx + 4 {
                    let (near, far) = common::pixel_ray_points(&scene, x, y, size);
                    let p = near + (far - near) * ((1.0 - near.z) / (far.z - near.z));
                    assert!(
                        p.y > 0.1 && p.x.abs() < 1.5,
                        "pixel ({x}, {y}) sees the wall at {p}"
                    );
                    tex += floor_to_wall(p, e_floor, &textured) * (0.8 / PI);
                    mean += floor_to_wall(p, e_floor, &flat) * (0.8 / PI);
                }
            }
            (tex / 64.0, mean / 64.0)
        })
        .collect();
    for (&(cx, cy), (tex, mean)) in centres.iter().zip(&expected) {
        let apart = ((*mean - *tex).abs() / *tex).max_element();
        println!(
            "window at ({cx}, {cy}): integral {tex:.4} with the texture, {mean:.4} with Kd \
             ({:.0}% apart)",
            apart * 100.0
        );
        assert!(
            apart > 3.0 * bound,
            "the windows must tell the texture from Kd"
        );
    }
    let methods = [
        (
            "hemisphere",
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 256,
                filter_radius: 0,
                ..Default::default()
            },
        ),
        (
            "vpl",
            GiSettings {
                method: GiMethod::Vpl,
                filter_radius: 0,
                vpl: VplSettings {
                    per_set: 256,
                    bounces: 1,
                    d_min_voxels: 0.0,
                    visibility: VplVisibility::None,
                    ..Default::default()
                },
                ..Default::default()
            },
        ),
        (
            "pathtrace",
            GiSettings {
                method: GiMethod::Pathtrace,
                rays: 64,
                bounces: Bounces::Fixed(1),
                accumulate_frames: 4,
                filter_radius: 0,
                ..Default::default()
            },
        ),
    ];
    for (name, gi) in methods {
        let img = render(gi);
        for (&centre, (tex, _)) in centres.iter().zip(&expected) {
            let got = window_mean(&img, &direct, centre, size);
            let rel = ((got - *tex).abs() / *tex).max_element();
            println!(
                "{name}, window at {centre:?}: indirect {got:.4} vs integral {tex:.4} \
                 ({:.1}% off)",
                rel * 100.0
            );
            assert!(
                rel < bound,
                "{name}, window at {centre:?}: indirect {got} vs integral {tex}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// A floor y = 0 (ρ 0.5) under a 0.5 m × 0.5 m panel at y = 0.5 facing down whose emission
/// map lights only the stripe u < 1/4 (x < −0.125 m; `Ke` 4 W/(m²·sr) times the map, sRGB
/// white on texels 0–1 of 8, black elsewhere), and no other light.
fn stripe_scene() -> (Scene, PathBuf) {
    let dir = scene_dir("stripe");
    image::RgbImage::from_fn(8, 1, |x, _| image::Rgb([if x < 2 { 255 } else { 0 }; 3]))
        .save(dir.join("stripe.png"))
        .unwrap();
    std::fs::write(
        dir.join("panel.mtl"),
        "newmtl panel\nKd 0 0 0\nKe 4 4 4\nmap_Ke stripe.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("panel.obj"),
        "mtllib panel.mtl\nusemtl panel\nv -0.25 0.5 -0.25\nv 0.25 0.5 -0.25\nv 0.25 0.5 0.25\n\
         v -0.25 0.5 0.25\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 -1 0\n\
         f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n",
    )
    .unwrap();
    let toml = dir.join("scene.toml");
    std::fs::write(
        &toml,
        r#"
[camera]
position = [0.0, 0.45, -0.6]
target = [0.0, 0.0, 0.0]
fov_y_deg = 50.0
near = 0.01
far = 20.0
[[objects]]
name = "panel"
mesh = "panel.obj"
[[objects]]
builtin = "quad"
scale = [2.0, 1.0, 2.0]
material = { albedo = 0.5 }
"#,
    )
    .unwrap();
    (Scene::load(&toml).expect("the stripe scene loads"), dir)
}

/// The irradiance at floor point `p` (normal +y) from the panel of [`stripe_scene`], whose
/// radiance at x is `radiance(x)`: E(p) = ∫ L(y) cos θ_y cos θ_p / d² dA with
/// cos θ_y = cos θ_p = 0.5 m / d (a horizontal panel facing down above a horizontal floor),
/// by the midpoint rule on 2.5 mm cells.
fn panel_to_floor(p: Vec3, radiance: &dyn Fn(f32) -> f32) -> f32 {
    let (n, cell) = (200, 0.5 / 200.0);
    let mut sum = 0.0;
    for i in 0..n {
        let x = -0.25 + (i as f32 + 0.5) * cell;
        let l = radiance(x);
        if l == 0.0 {
            continue;
        }
        for k in 0..n {
            let y = Vec3::new(x, 0.5, -0.25 + (k as f32 + 0.5) * cell);
            let d2 = (y - p).length_squared();
            sum += l * 0.25 / (d2 * d2);
        }
    }
    sum * cell * cell
}

/// Emission maps in the VPL emitter rays: the floor of [`stripe_scene`] is lit only by the
/// panel's source VPLs (`gi_vpl_emit`: triangles picked by `Ke` × the map's mean, points
/// resampled from 8 uniform candidates in proportion to the map, each carrying the map's texel
/// at its point over the resampling weight: an unbiased estimate this test checks). The floor's radiance in 8 × 8 windows under the stripe
/// (x ≈ −0.19 m) and under the black part (x ≈ +0.19 m) against ρ/π · [`panel_to_floor`] with
/// the panel's radiance `Ke` × the map as `voxel_maps.glsl` reads it at level 0 (the CPU twin:
/// 1 on the stripe, a ramp half a texel wide at its borders, including the wrapped one at
/// u = 0). Before, every point carried `Ke` × the map's mean, a uniform panel a quarter as
/// bright: its integral differs from the stripe's by far more than the bound in both windows
/// (asserted: more than 3 × the bound). The bound, 3%: 16 sets of 256 VPLs on a panel 0.5 m
/// above the floor, nearly all on the stripe, are a quadrature of a smooth integrand.
/// Measured on lavapipe: 0.1% under the stripe and beside it (0.2% / 0.1% with uniform points,
/// a quarter of them on the stripe), where the mean would be 21% and 58% off.
#[test]
fn an_emission_map_stripe_lights_the_floor_under_the_stripe() {
    let (scene, dir) = stripe_scene();
    let t = texture(&scene, "stripe");
    // The panel's texture coordinate at x is u = (x + 0.25)/0.5.
    let glow = |x: f32| sample_map_cpu(t, Vec2::new(2.0 * (x + 0.25), 0.5), -64.0).x;
    let stripe = |x: f32| 4.0 * glow(x);
    let mean = t.mean_linear.x;
    assert!((mean - 0.25).abs() < 1e-6, "two white texels of eight");
    let flat = |_: f32| 4.0 * mean;
    let ctx = common::context();
    let size = 64u32;
    let render = |gi: GiSettings| {
        let settings = RenderSettings {
            width: size,
            height: size,
            gi,
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        out.hdr
    };
    // The scene has no lights: the floor's only light is the panel's, which `--gi vpl`
    // brings by its emitter VPLs alone (under `--gi none` the panel lights the floor as direct
    // light, `direct_emitters`, which this image does not have). So nothing is subtracted.
    let img = render(GiSettings {
        method: GiMethod::Vpl,
        filter_radius: 0,
        vpl: VplSettings {
            per_set: 256,
            bounces: 1,
            d_min_voxels: 0.0,
            visibility: VplVisibility::None,
            ..Default::default()
        },
        ..Default::default()
    });
    let unlit = HdrImage {
        data: vec![[0.0; 3]; img.data.len()],
        ..img.clone()
    };
    let bound = 0.03;
    // Floor pixels whose points lie under the stripe and under the panel's black part.
    let floor_point = |x: u32, y: u32| {
        let (near, far) = common::pixel_ray_points(&scene, x, y, size);
        near + (far - near) * (near.y / (near.y - far.y))
    };
    let find = |target_x: f32| {
        (4..size - 4)
            .flat_map(|y| (4..size - 4).map(move |x| (x, y)))
            .min_by(|a, b| {
                let d = |(x, y): (u32, u32)| {
                    let p = floor_point(x, y);
                    (p.x - target_x).abs() + p.z.abs()
                };
                d(*a).total_cmp(&d(*b))
            })
            .expect("pixels")
    };
    for target_x in [-0.19f32, 0.19] {
        let (cx, cy) = find(target_x);
        let (mut tex, mut old) = (0.0, 0.0);
        for y in cy - 4..cy + 4 {
            for x in cx - 4..cx + 4 {
                let p = floor_point(x, y);
                assert!(
                    p.x.abs() < 0.5 && p.z.abs() < 0.5,
                    "pixel ({x}, {y}) sees the floor at {p}, under the panel"
                );
                tex += panel_to_floor(p, &stripe) * (0.5 / PI);
                old += panel_to_floor(p, &flat) * (0.5 / PI);
            }
        }
        let (tex, old) = (tex / 64.0, old / 64.0);
        let got = window_mean(&img, &unlit, (cx, cy), size);
        let rel = ((got - Vec3::splat(tex)).abs() / tex).max_element();
        println!(
            "window at ({cx}, {cy}) (x ≈ {target_x}): VPLs {got:.4} vs integral {tex:.4} \
             ({:.1}% off); the map's mean would give {old:.4}",
            rel * 100.0
        );
        assert!(
            ((old - tex) / tex).abs() > 3.0 * bound,
            "the window must tell the stripe from the mean"
        );
        assert!(
            rel < bound,
            "window at ({cx}, {cy}): VPLs {got} vs integral {tex}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

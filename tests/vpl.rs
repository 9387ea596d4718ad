//! `--gi vpl` (Thiedemann 2010, Ch. 7): one VPL against its closed form, the Mitsuba full-GI
//! references (better than direct light, two bounces better than one), samples that hit
//! nothing keep their share of the flux (or, with `--vpl-normalize valid`, the valid samples
//! share it all), spot VPLs sampled in the image-plane disk and on the cone agree, and the
//! geometry-aware filter removes the interleaving pattern. Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage, Metrics};
use voxgi::gi::vpl::{VplNormalize, VplSettings, VplSpotSampling, VplVisibility};
use voxgi::gi::{GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn vpl(v: VplSettings) -> GiSettings {
    GiSettings {
        method: GiMethod::Vpl,
        vpl: v,
        ..Default::default()
    }
}

fn render(ctx: &voxgi::vk::Context, scene: &Scene, gi: GiSettings, size: u32) -> HdrImage {
    let settings = RenderSettings {
        width: size,
        height: size,
        gi,
        ..Default::default()
    };
    let out = render_image(ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(ctx);
    assert!(
        out.hdr
            .data
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)),
        "finite, non-negative radiance"
    );
    out.hdr
}

fn scene_from(text: &str) -> Scene {
    Scene::from_toml_str(text, Path::new("test.toml"), Path::new(ROOT)).expect("scene parses")
}

/// The unit direction at polar cosine `c` and azimuth 2π u around unit axis `a`, exactly as
/// `around_axis` in glsl/include/gi_common.glsl builds it.
fn around_axis(a: Vec3, c: f32, u: f32) -> Vec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u;
    let t = if a.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let b1 = a.cross(t).normalize();
    let b2 = a.cross(b1);
    (b1 * (s * phi.cos()) + b2 * (s * phi.sin()) + a * c).normalize()
}

/// A spot light 1 m above a floor, narrow enough (0.5°) that its light map's texels are
/// 1e-4 m, and a wall facing the camera that the spot does not light, filling the frame.
const ONE_VPL_SCENE: &str = r#"
[camera]
position = [0.0, 1.0, -2.0]
target = [0.0, 1.0, 0.5]
fov_y_deg = 40.0

[[lights]]
kind = "spot"
position = [0.0, 1.0, 0.0]
direction = [0.0, -1.0, 0.0]
intensity_w_sr = 1000.0
cutoff_deg = 0.5
beam_deg = 0.5

[[objects]]
name = "floor"
builtin = "quad"
scale = 4.0
material = { albedo = 0.8 }

[[objects]]
name = "wall"
builtin = "quad"
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 1.0, 0.5]
scale = [4.0, 1.0, 2.0]
material = { albedo = 0.5 }
"#;

/// The floor's material in [`one_vpl_against_the_closed_form`].
#[derive(Clone, Copy, Debug)]
enum Sender {
    /// The scene's albedo 0.8.
    Lambert,
    /// Albedo 0.8 plus a Phong lobe (ρ_s, n).
    Phong(f32, f32),
    /// GGX with a base color, roughness and metalness.
    Ggx(Vec3, voxgi::scene::Ggx),
}

#[test]
fn one_vpl_gives_the_closed_form_irradiance() {
    one_vpl_against_the_closed_form(Sender::Lambert);
}

#[test]
fn one_phong_vpl_gives_the_closed_form_irradiance() {
    // The floor a Phong sender: ρ_s = 0.2, n = 10 (thesis §7.3).
    one_vpl_against_the_closed_form(Sender::Phong(0.2, 10.0));
}

/// GGX senders: a copper-like metal (only the specular lobe, F0 = the base color per channel)
/// and a half-metallic one (both lobes, the diffuse part with its (1 − F_d) factors).
#[test]
fn one_ggx_vpl_gives_the_closed_form_irradiance() {
    let copper = Vec3::new(0.955, 0.638, 0.538);
    for (base, roughness, metallic) in [(copper, 0.3, 1.0), (Vec3::new(0.9, 0.6, 0.3), 0.5, 0.5)] {
        one_vpl_against_the_closed_form(Sender::Ggx(
            base,
            voxgi::scene::Ggx {
                roughness,
                metallic,
            },
        ));
    }
}

/// One VPL on the floor (Lambert, Phong or GGX) lighting the wall.
fn one_vpl_against_the_closed_form(sender: Sender) {
    let floor = "scale = 4.0\nmaterial = { albedo = 0.8 }";
    let text = match sender {
        Sender::Lambert => ONE_VPL_SCENE.to_string(),
        Sender::Phong(rho_s, n) => ONE_VPL_SCENE.replace(
            floor,
            &format!(
                "scale = 4.0\nmaterial = {{ albedo = 0.8, specular = {rho_s}, shininess = {n} }}"
            ),
        ),
        Sender::Ggx(b, g) => ONE_VPL_SCENE.replace(
            floor,
            &format!(
                "scale = 4.0\nmaterial = {{ albedo = [{}, {}, {}], roughness = {}, metallic = {} }}",
                b.x, b.y, b.z, g.roughness, g.metallic
            ),
        ),
    };
    assert!(
        matches!(sender, Sender::Lambert) || text != ONE_VPL_SCENE,
        "the floor is glossy"
    );
    let scene = scene_from(&text);
    let ctx = common::context();
    let size = 96;
    let d_min_voxels = 20.0;
    let h = voxgi::voxel::gpu::VoxelSettings::default()
        .grid_for(&scene, 0.0)
        .expect("grid")
        .voxel_diagonal_m();
    let d_min_m2 = (d_min_voxels * h).powi(2);
    // One set of one VPL, one bounce, no filter: the image is the direct light plus one VPL.
    let settings = |visibility| GiSettings {
        filter_radius: 0,
        ..vpl(VplSettings {
            per_set: 1,
            pattern: [1, 1],
            bounces: 1,
            d_min_voxels,
            visibility,
            ..Default::default()
        })
    };
    // The VPL: Halton point 1 = (1/2, 1/3) (base 2, 3) on the spot's cone, cos θ =
    // 1 - u (1 - cos α), azimuth 2π/3, hitting the floor y = 0 from (0, 1, 0).
    let cos_a = 0.5f32.to_radians().cos();
    let dir = around_axis(Vec3::NEG_Y, 1.0 - 0.5 * (1.0 - cos_a), 1.0 / 3.0);
    let light = Vec3::new(0.0, 1.0, 0.0);
    let vpl_at = light + dir * (1.0 / -dir.y);
    // Φ_in = I Ω, the flux the light sends into the sample's solid angle Ω = 2π (1 - cos α);
    // the beam equals the cutoff, so the falloff is 1 on the whole cone. A Lambert VPL
    // reflects Φ_VPL = ρ Φ_in (§7.2).
    let omega = 2.0 * std::f32::consts::PI * (1.0 - cos_a);
    let phi_in = 1000.0 * omega;
    let wall_n = Vec3::NEG_Z;
    for visibility in [VplVisibility::None, VplVisibility::Voxel] {
        let img = render(&ctx, &scene, settings(visibility), size);
        let mut checked = 0;
        for (x, y) in [(20, 20), (48, 30), (70, 25), (30, 50), (60, 45)] {
            // Where the pixel's camera ray meets the wall z = 0.5 (y down in pixel rows).
            let (near, far) = common::pixel_ray_points(&scene, x, y, size);
            let t = (0.5 - near.z) / (far.z - near.z);
            let p = near + (far - near) * t;
            assert!(p.y > 0.3 && p.x.abs() < 1.9, "pixel ({x}, {y}) at {p}");
            let to_vpl = vpl_at - p;
            let d2 = to_vpl.length_squared();
            let w = to_vpl / d2.sqrt();
            let cos_p = wall_n.dot(w);
            let cos_v = -Vec3::Y.dot(w);
            // The VPL's intensity toward the wall point (thesis §7.3): I = Φ_VPL / π cos θ_VPL
            // (Lambert); a Phong sender adds ρ_s Φ_in (n+2)/(2π) cos^n α cos θ_VPL, α from the
            // mirror direction of the incident light. Any sender: I = f(wi, wo) Φ_in cos θ_VPL,
            // the radiance f E of a small patch dA times its projected area, with E dA = Φ_in;
            // wi toward the light (-dir), wo toward the wall point (-w), f = ρ/π for Lambert.
            let intensity = match sender {
                Sender::Lambert => Vec3::splat(0.8 * phi_in / std::f32::consts::PI * cos_v),
                Sender::Phong(rho_s, n) => {
                    let mirror = Vec3::new(dir.x, -dir.y, dir.z);
                    let cos_a = mirror.dot(-w).max(0.0);
                    Vec3::splat(
                        (0.8 / std::f32::consts::PI
                            + rho_s * (n + 2.0) / (2.0 * std::f32::consts::PI) * cos_a.powf(n))
                            * phi_in
                            * cos_v,
                    )
                }
                Sender::Ggx(b, g) => {
                    voxgi::scene::ggx_brdf(b, g, Vec3::Y, -dir, -w) * (phi_in * cos_v)
                }
            };
            // E = I cos θ_P / (d_min + d²) (§7.3); the wall's radiance L = ρ_wall / π E.
            let expected = intensity * (0.5 / std::f32::consts::PI * cos_p / (d_min_m2 + d2));
            let got = Vec3::from(img.data[(y * size + x) as usize]);
            println!("{sender:?} {visibility:?} ({x}, {y}): {got} vs {expected}");
            for c in 0..3 {
                let rel = (got[c] - expected[c]).abs() / expected[c];
                assert!(
                    rel < 0.01,
                    "{sender:?}, {visibility:?}: pixel ({x}, {y}) at {p}, channel {c}: {} vs \
                     closed form {} ({:.2}% off)",
                    got[c],
                    expected[c],
                    rel * 100.0
                );
            }
            checked += 1;
        }
        assert_eq!(checked, 5);
    }
}

/// GGX receivers (issue #14): one Lambert VPL on the floor of [`ONE_VPL_SCENE`] lighting a GGX
/// wall, whose indirect radiance is its whole BRDF toward the camera times the VPL's irradiance,
/// f_r(wi, wo) · I cos θ_P / (d_min + d²) (the gather's formula with brdf_ggx instead of ρ/π; wi
/// toward the VPL, wo toward the camera), within 1% (G-buffer F0 and roughness are 16-bit
/// floats). Cases: a copper-like metal (only the lobe) and a half-metallic dielectric (both
/// lobes); and the roughness floor `--vpl-min-roughness`: a smooth metal (r = 0.15) is shaded
/// with r = max(0.15, floor), i.e. r = 0.15 at floor 0 and r = 0.5 at floor 0.5 — before, every
/// GGX pixel got (1 − m)·b/π·E, black for the metals.
#[test]
fn one_vpl_lights_a_ggx_receiver_with_its_whole_brdf() {
    let copper = Vec3::new(0.955, 0.638, 0.538);
    let g = |roughness, metallic| voxgi::scene::Ggx {
        roughness,
        metallic,
    };
    // (base, material, roughness floor, the roughness the wall is shaded with)
    let cases = [
        (copper, g(0.4, 1.0), 0.2, 0.4),
        (Vec3::new(0.9, 0.6, 0.3), g(0.5, 0.5), 0.2, 0.5),
        (copper, g(0.15, 1.0), 0.0, 0.15),
        (copper, g(0.15, 1.0), 0.5, 0.5),
    ];
    let ctx = common::context();
    let size = 96;
    let d_min_voxels = 20.0;
    let wall = "scale = [4.0, 1.0, 2.0]\nmaterial = { albedo = 0.5 }";
    assert!(ONE_VPL_SCENE.contains(wall));
    for (base, ggx, floor, shaded) in cases {
        let text = ONE_VPL_SCENE.replace(
            wall,
            &format!(
                "scale = [4.0, 1.0, 2.0]\nmaterial = {{ albedo = [{}, {}, {}], roughness = {}, \
                 metallic = {} }}",
                base.x, base.y, base.z, ggx.roughness, ggx.metallic
            ),
        );
        let scene = scene_from(&text);
        let h = voxgi::voxel::gpu::VoxelSettings::default()
            .grid_for(&scene, 0.0)
            .expect("grid")
            .voxel_diagonal_m();
        let d_min_m2 = (d_min_voxels * h).powi(2);
        let settings = GiSettings {
            filter_radius: 0,
            ..vpl(VplSettings {
                per_set: 1,
                pattern: [1, 1],
                bounces: 1,
                d_min_voxels,
                min_roughness: floor,
                visibility: VplVisibility::None,
                ..Default::default()
            })
        };
        let img = render(&ctx, &scene, settings, size);
        // The VPL as in `one_vpl_against_the_closed_form`: Halton point (1/2, 1/3) on the
        // spot's 0.5° cone, on the floor; a Lambert VPL of Φ_VPL = 0.8 Φ_in, Φ_in = I Ω.
        let cos_a = 0.5f32.to_radians().cos();
        let dir = around_axis(Vec3::NEG_Y, 1.0 - 0.5 * (1.0 - cos_a), 1.0 / 3.0);
        let light = Vec3::new(0.0, 1.0, 0.0);
        let vpl_at = light + dir * (1.0 / -dir.y);
        let phi_in = 1000.0 * 2.0 * std::f32::consts::PI * (1.0 - cos_a);
        let wall_n = Vec3::NEG_Z;
        let shaded_ggx = voxgi::scene::Ggx {
            roughness: shaded,
            ..ggx
        };
        for (x, y) in [(20, 20), (48, 30), (70, 25), (30, 50), (60, 45)] {
            let (near, far) = common::pixel_ray_points(&scene, x, y, size);
            let p = near + (far - near) * ((0.5 - near.z) / (far.z - near.z));
            assert!(p.y > 0.3 && p.x.abs() < 1.9, "pixel ({x}, {y}) at {p}");
            let to_vpl = vpl_at - p;
            let d2 = to_vpl.length_squared();
            let w = to_vpl / d2.sqrt();
            let (cos_p, cos_v) = (wall_n.dot(w), -Vec3::Y.dot(w));
            let intensity = 0.8 * phi_in / std::f32::consts::PI * cos_v;
            let wo = (scene.camera.position - p).normalize();
            let f = voxgi::scene::ggx_brdf(base, shaded_ggx, wall_n, w, wo);
            let expected = f * (intensity * cos_p / (d_min_m2 + d2));
            let got = Vec3::from(img.data[(y * size + x) as usize]);
            println!("{ggx:?} floor {floor}: ({x}, {y}): {got} vs {expected}");
            let rel = ((got - expected).abs() / expected).max_element();
            assert!(
                rel < 0.01,
                "{ggx:?}, roughness floor {floor}: pixel ({x}, {y}) at {p}: {got} vs closed \
                 form {expected} ({:.2}% off)",
                rel * 100.0
            );
        }
    }
}

/// Phong receivers under the roughness floor: the wall of [`ONE_VPL_SCENE`] made normalized
/// Phong (ρ_d = 0.3, ρ_s = 0.5, n = 200), lit by the same Lambert VPL, near the highlight (the
/// VPL's mirror image through the wall reaches the camera at y ≈ 0.17). Its radiance is
/// (ρ_d/π + ρ_s (n'+2)/(2π) cos^n' α) · I cos θ_P / (d_min + d²), α between the VPL's mirror
/// direction and the camera, n' = n at floor 0 and n' = min(n, 2/R⁴ − 2) = 76.1 at R = 0.4
/// (the exponent of the GGX width α = R², as the gather caps it), within 1%.
#[test]
fn one_vpl_lights_a_phong_receiver_with_its_exponent_capped_by_the_floor() {
    let ctx = common::context();
    let size = 96;
    let d_min_voxels = 20.0;
    let wall = "scale = [4.0, 1.0, 2.0]\nmaterial = { albedo = 0.5 }";
    let text = ONE_VPL_SCENE.replace(
        wall,
        "scale = [4.0, 1.0, 2.0]\nmaterial = { albedo = 0.3, specular = 0.5, shininess = 200.0 }",
    );
    assert_ne!(text, ONE_VPL_SCENE);
    let scene = scene_from(&text);
    let h = voxgi::voxel::gpu::VoxelSettings::default()
        .grid_for(&scene, 0.0)
        .expect("grid")
        .voxel_diagonal_m();
    let d_min_m2 = (d_min_voxels * h).powi(2);
    let cos_a = 0.5f32.to_radians().cos();
    let dir = around_axis(Vec3::NEG_Y, 1.0 - 0.5 * (1.0 - cos_a), 1.0 / 3.0);
    let vpl_at = Vec3::new(0.0, 1.0, 0.0) + dir * (1.0 / -dir.y);
    let phi_in = 1000.0 * 2.0 * std::f32::consts::PI * (1.0 - cos_a);
    let wall_n = Vec3::NEG_Z;
    for (floor, shininess) in [(0.0f32, 200.0f32), (0.4, 2.0 / 0.4f32.powi(4) - 2.0)] {
        let settings = GiSettings {
            filter_radius: 0,
            ..vpl(VplSettings {
                per_set: 1,
                pattern: [1, 1],
                bounces: 1,
                d_min_voxels,
                min_roughness: floor,
                visibility: VplVisibility::None,
                ..Default::default()
            })
        };
        let img = render(&ctx, &scene, settings, size);
        let mut peak = 0.0f32;
        for (x, y) in [(48, 86), (47, 89), (48, 91), (49, 92), (46, 90)] {
            let (near, far) = common::pixel_ray_points(&scene, x, y, size);
            let p = near + (far - near) * ((0.5 - near.z) / (far.z - near.z));
            assert!(p.y > 0.05 && p.x.abs() < 1.9, "pixel ({x}, {y}) at {p}");
            let to_vpl = vpl_at - p;
            let d2 = to_vpl.length_squared();
            let w = to_vpl / d2.sqrt();
            let (cos_p, cos_v) = (wall_n.dot(w), -Vec3::Y.dot(w));
            let intensity = 0.8 * phi_in / std::f32::consts::PI * cos_v;
            let wo = (scene.camera.position - p).normalize();
            let mirror = 2.0 * wall_n.dot(w) * wall_n - w;
            let lobe = mirror.dot(wo).max(0.0).powf(shininess);
            peak = peak.max(lobe);
            let f = 0.3 / std::f32::consts::PI
                + 0.5 * (shininess + 2.0) / (2.0 * std::f32::consts::PI) * lobe;
            let expected = f * intensity * cos_p / (d_min_m2 + d2);
            let got = img.data[(y * size + x) as usize][0];
            println!("floor {floor} (n' {shininess:.1}): ({x}, {y}): {got} vs {expected}, cos^n' {lobe:.3}");
            let rel = (got - expected).abs() / expected;
            assert!(
                rel < 0.01,
                "floor {floor}: pixel ({x}, {y}) at {p}: {got} vs closed form {expected} \
                 ({:.2}% off)",
                rel * 100.0
            );
        }
        assert!(
            peak > 0.3,
            "the pixels see the highlight (cos^n' up to {peak})"
        );
    }
}

fn metrics(scene_arg: &str, reference: &str, gi: GiSettings) -> Metrics {
    let arg = if scene_arg.ends_with(".toml") {
        format!("{ROOT}/{scene_arg}")
    } else {
        scene_arg.to_string()
    };
    let scene = load_scene_arg(Some(&arg)).expect("scene loads");
    let ctx = common::context();
    let img = render(&ctx, &scene, gi, 256);
    let r = HdrImage::load(Path::new(ROOT).join(format!("assets/references/{reference}_gi.exr")))
        .expect("reference");
    compare(&r, &img, None).expect("same size")
}

#[test]
fn vpls_beat_direct_light_and_two_bounces_beat_one_on_every_test_scene() {
    // Bounds (relMSE, FLIP) are the two-bounce values measured at 256², 8 VPLs per set and
    // light, 4×4 sets, plus about 20% (cornell 0.0564 / 0.297, cornell_bunny 0.0460 / 0.260,
    // point_light 0.0071 / 0.054; direct light 0.384 / 0.698, 0.315 / 0.647, 0.0127 / 0.077).
    for (scene, reference, (bound, flip_bound)) in [
        ("cornell", "cornell", (0.07, 0.36)),
        (
            "assets/scenes/cornell_bunny.toml",
            "cornell_bunny",
            (0.056, 0.31),
        ),
        (
            "assets/scenes/point_light.toml",
            "point_light",
            (0.0086, 0.065),
        ),
    ] {
        let direct = metrics(scene, reference, GiSettings::default());
        let with = |bounces| {
            metrics(
                scene,
                reference,
                vpl(VplSettings {
                    per_set: 8,
                    bounces,
                    ..Default::default()
                }),
            )
        };
        let (one, two) = (with(1), with(2));
        println!(
            "{reference}: direct relMSE {:.4} FLIP {:.4}; VPL 1 bounce {:.4} / {:.4}; \
             2 bounces {:.4} / {:.4}",
            direct.rel_mse,
            direct.flip_mean,
            one.rel_mse,
            one.flip_mean,
            two.rel_mse,
            two.flip_mean
        );
        assert!(
            two.rel_mse < direct.rel_mse && two.flip_mean < direct.flip_mean,
            "{reference}: VPLs no better than direct light"
        );
        assert!(
            two.rel_mse < one.rel_mse,
            "{reference}: two bounces ({}) no closer than one ({})",
            two.rel_mse,
            one.rel_mse
        );
        assert!(
            two.rel_mse < bound && two.flip_mean < flip_bound,
            "{reference}: relMSE {} ≥ {bound} or FLIP {} ≥ {flip_bound}",
            two.rel_mse,
            two.flip_mean
        );
    }
}

/// A point light over a floor, a wall as the receiver; `ceiling` adds a black ceiling above
/// the light, which turns the samples that leave the scene upwards into valid VPLs of zero
/// flux.
fn open_or_closed(ceiling: bool) -> Scene {
    let mut text = String::from(
        r#"
[camera]
position = [0.0, 0.4, -1.5]
target = [0.0, 0.3, 1.0]
fov_y_deg = 45.0

[[lights]]
kind = "point"
position = [0.0, 0.5, 0.0]
intensity_w_sr = 5.0

[[objects]]
name = "floor"
builtin = "quad"
scale = 6.0
material = { albedo = 0.8 }

[[objects]]
name = "wall"
builtin = "quad"
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 0.2, 1.0]
scale = [2.0, 1.0, 0.4]
material = { albedo = 0.5 }
"#,
    );
    if ceiling {
        text.push_str(
            r#"
[[objects]]
name = "ceiling"
builtin = "quad"
translate = [0.0, 3.0, 0.0]
scale = 40.0
material = { albedo = 0.0 }
"#,
        );
    }
    scene_from(&text)
}

/// The mean of all channels of `a - b`.
fn mean_difference(a: &HdrImage, b: &HdrImage) -> f64 {
    let sum: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| (0..3).map(move |c| f64::from(p[c] - q[c])))
        .sum();
    sum / (a.data.len() * 3) as f64
}

#[test]
fn samples_that_hit_nothing_keep_their_share_of_the_flux() {
    // Open: the upper half of the point light's sphere of directions hits nothing (but the
    // wall), so about half the samples are invalid. Closed: a black ceiling catches them, so
    // none is invalid, and the VPLs on it carry zero flux. The flux reaching the floor and the
    // wall is the same, so the expected indirect light is: normalizing by all K samples of the
    // emission domain (Φ_VPL = ρ I Ω / K) gives it, normalizing by the valid count would
    // double the open scene's. The samples are the same Halton points in both, so only the
    // light maps' rasterization differs (the ceiling moves the cube maps' depth range).
    let ctx = common::context();
    let gi = GiSettings {
        filter_radius: 0,
        ..vpl(VplSettings {
            per_set: 64,
            pattern: [1, 1],
            bounces: 1,
            visibility: VplVisibility::None,
            // d_min is relative to the voxel grid, which the ceiling widens.
            d_min_voxels: 0.0,
            ..Default::default()
        })
    };
    let size = 64;
    let mut indirect = Vec::new();
    for ceiling in [false, true] {
        let scene = open_or_closed(ceiling);
        let lit = render(&ctx, &scene, gi, size);
        let direct = render(&ctx, &scene, GiSettings::default(), size);
        indirect.push(mean_difference(&lit, &direct));
    }
    let ratio = indirect[0] / indirect[1];
    println!(
        "indirect open {:.4e}, closed {:.4e}, ratio {ratio:.4}",
        indirect[0], indirect[1]
    );
    assert!(indirect[1] > 0.0, "the closed scene has indirect light");
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "open / closed indirect light {ratio}: invalid samples changed the flux"
    );
}

/// Radical inverse of `i` in base `b`, as `halton` in glsl/include/vpl.glsl.
fn halton(mut i: u32, b: u32) -> f32 {
    let (mut f, mut r) = (1.0f32, 0.0f32);
    let inv = 1.0 / b as f32;
    while i > 0 {
        f *= inv;
        r += f * (i % b) as f32;
        i /= b;
    }
    r
}

/// The direction of Halton point `j` of a spot with axis `axis` and cone half-angle
/// `cutoff_deg`, and its weight over K samples times K (sr): on the cone uniform in solid
/// angle (Ω) or uniform in the image-plane disk (π tan²α cos³θ), as gi_vpl_generate.comp.
fn spot_sample(axis: Vec3, cutoff_deg: f32, j: u32, sampling: VplSpotSampling) -> (Vec3, f32) {
    let (ux, uy) = (halton(j, 2), halton(j, 3));
    let cos_a = cutoff_deg.to_radians().cos();
    match sampling {
        VplSpotSampling::SolidAngle => (
            around_axis(axis, 1.0 - ux * (1.0 - cos_a), uy),
            2.0 * std::f32::consts::PI * (1.0 - cos_a),
        ),
        VplSpotSampling::Disk => {
            let tan2 = (1.0 - cos_a * cos_a) / (cos_a * cos_a);
            let c = 1.0 / (1.0 + tan2 * ux).sqrt();
            (
                around_axis(axis, c, uy),
                std::f32::consts::PI * tan2 * c * c * c,
            )
        }
    }
}

/// A spot 1 m above a floor that spans x from -3 m to `edge_x_m`, aimed straight down with a
/// 30° cone of uniform intensity, and a wall at z = 1 m facing the camera, out of the cone.
fn spot_over_floor_edge(edge_x_m: f32) -> Scene {
    let (width, center) = (edge_x_m + 3.0, (edge_x_m - 3.0) / 2.0);
    scene_from(&format!(
        r#"
[camera]
position = [0.0, 0.8, -2.0]
target = [0.0, 0.5, 0.5]
fov_y_deg = 45.0

[[lights]]
kind = "spot"
position = [0.0, 1.0, 0.0]
direction = [0.0, -1.0, 0.0]
intensity_w_sr = 4.0
cutoff_deg = 30.0
beam_deg = 30.0

[[objects]]
name = "floor"
builtin = "quad"
translate = [{center}, 0.0, -0.25]
scale = [{width}, 1.0, 2.5]
material = {{ albedo = 0.8 }}

[[objects]]
name = "wall"
builtin = "quad"
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 0.75, 1.0]
scale = [6.0, 1.0, 1.5]
material = {{ albedo = 0.5 }}
"#
    ))
}

#[test]
fn renormalizing_by_the_valid_samples_scales_the_indirect_light_by_k_over_their_count() {
    // With `valid`, every VPL of a set and light carries K / V times its `all` flux (V the
    // set's samples that hit geometry), and the indirect light (every bounce) is linear in the
    // first-bounce fluxes: with one set, indirect(valid) = indirect(all) × K / V exactly, up
    // to float rounding. V is counted here on the CPU from the same Halton points: the floor
    // ends at x = 0 under the spot, so a sample is valid iff it meets y = 0 at x < 0; every
    // sample lands at least 2 cm from the edge (checked), several light-map texels (the
    // 256² map spans 2 tan 30° ≈ 1.15 m there), so the GPU's count cannot differ.
    let ctx = common::context();
    let k = 16u32;
    let size = 64;
    let gi = |normalize, spot_sampling| GiSettings {
        filter_radius: 0,
        ..vpl(VplSettings {
            per_set: k,
            pattern: [1, 1],
            normalize,
            spot_sampling,
            ..Default::default()
        })
    };
    let half = spot_over_floor_edge(0.0);
    let direct = render(&ctx, &half, GiSettings::default(), size);
    for sampling in [VplSpotSampling::SolidAngle, VplSpotSampling::Disk] {
        let hits_x: Vec<f32> = (1..=k)
            .map(|j| {
                let (d, _) = spot_sample(Vec3::NEG_Y, 30.0, j, sampling);
                d.x / -d.y
            })
            .collect();
        assert!(
            hits_x.iter().all(|x| x.abs() > 0.02),
            "{sampling:?}: a sample within 2 cm of the floor's edge: {hits_x:?}"
        );
        let valid = hits_x.iter().filter(|&&x| x < 0.0).count() as f64;
        assert!(
            valid > 0.0 && valid < f64::from(k),
            "some samples miss, not all"
        );
        let all = mean_difference(
            &render(&ctx, &half, gi(VplNormalize::All, sampling), size),
            &direct,
        );
        let renormalized = mean_difference(
            &render(&ctx, &half, gi(VplNormalize::Valid, sampling), size),
            &direct,
        );
        let expected = f64::from(k) / valid;
        println!(
            "{sampling:?}: {valid} of {k} valid; indirect all {all:.4e}, valid {renormalized:.4e}, \
             ratio {:.5} (K / V = {expected:.5})",
            renormalized / all
        );
        assert!(all > 0.0, "{sampling:?}: indirect light");
        assert!(
            (renormalized / all / expected - 1.0).abs() < 1e-3,
            "{sampling:?}: valid / all = {} instead of K / V = {expected}",
            renormalized / all
        );
        // Nothing misses when the floor spans the whole cone: V = K, the same image.
        let full = spot_over_floor_edge(3.0);
        let a = render(&ctx, &full, gi(VplNormalize::All, sampling), size);
        let b = render(&ctx, &full, gi(VplNormalize::Valid, sampling), size);
        assert!(
            a.data == b.data,
            "{sampling:?}: no sample misses, yet the images differ"
        );
    }
}

/// The mean indirect light (`lit - direct`, all channels) of each 4×4-interleaving set: over
/// the pixels (x, y) with the same (x mod 4, y mod 4), which the unfiltered VPL image shades
/// with one set each (§7.3.2).
fn set_means(lit: &HdrImage, direct: &HdrImage) -> Vec<f64> {
    let mut sums = vec![(0.0f64, 0usize); 16];
    let w = lit.width as usize;
    for (i, (p, q)) in lit.data.iter().zip(&direct.data).enumerate() {
        let (x, y) = (i % w, i / w);
        let s = &mut sums[(y % 4) * 4 + x % 4];
        s.0 += (0..3).map(|c| f64::from(p[c] - q[c])).sum::<f64>();
        s.1 += 3;
    }
    sums.iter().map(|&(s, n)| s / n as f64).collect()
}

/// Mean and standard error of the mean of `v`.
fn mean_and_error(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn spot_vpls_from_the_image_plane_disk_and_the_cone_agree() {
    // Both samplings estimate the same one-bounce integral over the spot's cone (the disk's
    // weight π tan²α cos³θ / K is the solid angle of its area element, gi_vpl_generate.comp),
    // so their frame means differ only by their sampling errors. Each of the 16 interleaving
    // sets is an estimator of its own (64 Halton points), and without the filter each shades
    // one pixel of every 4×4 tile: the spread of the 16 per-set means gives each estimate's
    // standard error (conservatively: the sets' pixels also differ slightly in place), and the
    // two means must agree within 3 standard errors of their difference. The weights' sums
    // are checked against the cone's solid angle Ω on the CPU for the same points (the
    // estimators' error for a constant integrand).
    let ctx = common::context();
    let size = 64;
    let (cutoff_deg, per_set, sets) = (50.0f32, 64u32, 16u32);
    let axis = Vec3::new(0.0, -1.0, 0.3).normalize();
    let scene = floor_and_wall(&format!(
        "[[lights]]\nkind = \"spot\"\nposition = [0.3, 1.2, 0.2]\ndirection = [0.0, -1.0, 0.3]\n\
         intensity_w_sr = 4.0\ncutoff_deg = {cutoff_deg}"
    ));
    let omega = 2.0 * std::f64::consts::PI * (1.0 - f64::from(cutoff_deg.to_radians().cos()));
    for sampling in [VplSpotSampling::SolidAngle, VplSpotSampling::Disk] {
        let n = per_set * sets;
        let sum: f64 = (1..=n)
            .map(|j| f64::from(spot_sample(axis, cutoff_deg, j, sampling).1))
            .sum();
        let error = sum / f64::from(n) / omega - 1.0;
        println!("{sampling:?}: weights' sum / Ω - 1 = {error:.2e}");
        // 1024 Halton points integrate the smooth cos³θ over the disk to well below 1%.
        assert!(
            error.abs() < 0.01,
            "{sampling:?}: weights sum to Ω (1 {error:+})"
        );
    }
    let direct = render(&ctx, &scene, GiSettings::default(), size);
    let estimate = |spot_sampling| {
        let lit = render(
            &ctx,
            &scene,
            GiSettings {
                filter_radius: 0,
                ..vpl(VplSettings {
                    per_set,
                    bounces: 1,
                    d_min_voxels: 0.0,
                    spot_sampling,
                    ..Default::default()
                })
            },
            size,
        );
        mean_and_error(&set_means(&lit, &direct))
    };
    let ((cone, e_cone), (disk, e_disk)) = (
        estimate(VplSpotSampling::SolidAngle),
        estimate(VplSpotSampling::Disk),
    );
    let bound = 3.0 * (e_cone * e_cone + e_disk * e_disk).sqrt();
    println!(
        "mean indirect cone {cone:.4e} ± {e_cone:.1e}, disk {disk:.4e} ± {e_disk:.1e}; \
         difference {:.2e}, bound {bound:.2e}",
        disk - cone
    );
    assert!(cone > 0.0 && disk > 0.0, "indirect light");
    assert!(
        (disk - cone).abs() < bound,
        "disk {disk} vs cone {cone}: more than 3 standard errors apart"
    );
}

/// Energy of the N×M-periodic part of `img`'s luminance-free channel sum, as a fraction of
/// its energy without the mean: Σ |F(k W/N, l H/M)|² over (k, l) ≠ (0, 0) divided by
/// W H Σ (I - mean)², which by Parseval is the sum of |F|² over every frequency but 0.
fn periodic_energy_fraction(img: &[f64], w: usize, h: usize, n: usize, m: usize) -> f64 {
    let mean = img.iter().sum::<f64>() / img.len() as f64;
    let total: f64 = (w * h) as f64 * img.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let mut periodic = 0.0;
    for k in 0..n {
        for l in 0..m {
            if k == 0 && l == 0 {
                continue;
            }
            let (u, v) = ((k * w / n) as f64, (l * h / m) as f64);
            let (mut re, mut im) = (0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let a = -2.0
                        * std::f64::consts::PI
                        * (u * x as f64 / w as f64 + v * y as f64 / h as f64);
                    re += img[y * w + x] * a.cos();
                    im += img[y * w + x] * a.sin();
                }
            }
            periodic += re * re + im * im;
        }
    }
    periodic / total.max(1e-300)
}

#[test]
fn the_filter_removes_the_interleaving_pattern() {
    let scene = load_scene_arg(None).expect("the built-in Cornell box");
    let ctx = common::context();
    let size = 128;
    let direct = render(&ctx, &scene, GiSettings::default(), size);
    let settings = VplSettings {
        per_set: 4,
        bounces: 1,
        ..Default::default()
    };
    let mut fractions = Vec::new();
    for filter_radius in [0, GiSettings::default().filter_radius] {
        let lit = render(
            &ctx,
            &scene,
            GiSettings {
                filter_radius,
                ..vpl(settings)
            },
            size,
        );
        let indirect: Vec<f64> = lit
            .data
            .iter()
            .zip(&direct.data)
            .map(|(p, q)| (0..3).map(|c| f64::from(p[c] - q[c])).sum())
            .collect();
        let s = size as usize;
        fractions.push(periodic_energy_fraction(&indirect, s, s, 4, 4));
    }
    println!(
        "4×4-periodic energy of the indirect light: unfiltered {:.3e}, filtered {:.3e}",
        fractions[0], fractions[1]
    );
    // Measured: 2.9e-2 unfiltered, 3.6e-4 filtered. A separable Gaussian of σ = radius/2 = 2
    // pixels, applied twice per axis (σ = 2√2), passes exp(-2π² σ² f²) = 5e-5 of the amplitude
    // at the pattern's lowest frequency f = 1/4 per pixel; what remains comes from the
    // geometry-aware weights, which stop at edges, and from the image's own content at those
    // 15 of 128² frequencies (15 / 128² = 9e-4 of a white spectrum).
    assert!(
        fractions[0] > 0.01,
        "the unfiltered image shows the pattern"
    );
    assert!(
        fractions[1] < 1e-3 && fractions[1] < fractions[0] / 20.0,
        "the pattern survives the filter"
    );
}

#[test]
fn odd_frame_sizes_are_covered_and_splatting_equals_the_gather() {
    // 67×45 is no multiple of the 4×4 pattern: the last blocks are partly outside the frame.
    // In the one-VPL scene every set's VPL lies within 1 cm of the spot's axis on the floor, in
    // front of the wall, so every wall pixel receives light from its set: a pixel the split
    // or its inverse missed would keep none.
    let scene = scene_from(ONE_VPL_SCENE);
    let ctx = common::context();
    let (w, h) = (67u32, 45u32);
    let run = |shading| {
        let settings = RenderSettings {
            width: w,
            height: h,
            gi: GiSettings {
                filter_radius: 0,
                ..vpl(VplSettings {
                    per_set: 1,
                    bounces: 1,
                    visibility: VplVisibility::None,
                    shading,
                    ..Default::default()
                })
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        out.hdr
    };
    let gather = run(voxgi::gi::vpl::VplShading::Gather);
    let splat = run(voxgi::gi::vpl::VplShading::Splat);
    for y in 0..h {
        for x in 0..w {
            let (near, far) = scene.camera.pixel_ray_points(x, y, w, h);
            let t = (0.5 - near.z) / (far.z - near.z);
            let p = near + (far - near) * t;
            assert!(
                p.x.abs() < 2.0 && p.y > 0.0 && p.y < 2.0,
                "({x}, {y}) sees the wall"
            );
            let g = gather.data[(y * w + x) as usize];
            assert!(
                g.iter().all(|c| c.is_finite() && *c > 0.0),
                "pixel ({x}, {y}) got no indirect light: {g:?}"
            );
        }
    }
    // The same sums in another order: equal to float rounding.
    for (g, s) in gather.data.iter().zip(&splat.data) {
        for c in 0..3 {
            assert!(
                (g[c] - s[c]).abs() <= 1e-5 * g[c].abs().max(1e-6),
                "splat {s:?} vs gather {g:?}"
            );
        }
    }
}

/// A floor and a wall facing the camera lit by `light` (a `[[lights]]` table).
fn floor_and_wall(light: &str) -> Scene {
    scene_from(&format!(
        r#"
[camera]
position = [0.0, 0.8, -2.0]
target = [0.0, 0.5, 0.5]
fov_y_deg = 45.0

{light}

[[objects]]
name = "floor"
builtin = "quad"
scale = 3.0
material = {{ albedo = 0.8 }}

[[objects]]
name = "wall"
builtin = "quad"
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 0.75, 1.0]
scale = [3.0, 1.0, 1.5]
material = {{ albedo = 0.5 }}
"#
    ))
}

#[test]
fn vpls_agree_with_hemisphere_sampling_for_every_light_kind() {
    // One bounce of the same light maps estimated two independent ways: VPLs from the maps
    // (Φ from the stored radiance) and hemisphere rays reading the maps at their hits. Means of
    // the indirect light over the frame; d_min 0 and no filter, so neither is biased but for
    // the voxel visibility both share.
    let ctx = common::context();
    let size = 64;
    for (kind, light) in [
        (
            "point",
            "[[lights]]\nkind = \"point\"\nposition = [0.3, 0.8, 0.2]\nintensity_w_sr = 2.0",
        ),
        (
            "spot",
            "[[lights]]\nkind = \"spot\"\nposition = [0.3, 1.2, 0.2]\ndirection = [0.0, -1.0, 0.3]\n\
             intensity_w_sr = 4.0\ncutoff_deg = 50.0",
        ),
        (
            "directional",
            "[[lights]]\nkind = \"directional\"\ndirection = [0.3, -1.0, 0.4]\nirradiance_w_m2 = 2.0",
        ),
    ] {
        let scene = floor_and_wall(light);
        let direct = render(&ctx, &scene, GiSettings::default(), size);
        let v = render(
            &ctx,
            &scene,
            GiSettings {
                filter_radius: 0,
                ..vpl(VplSettings {
                    per_set: 64,
                    bounces: 1,
                    d_min_voxels: 0.0,
                    ..Default::default()
                })
            },
            size,
        );
        let hemi = render(
            &ctx,
            &scene,
            GiSettings {
                method: GiMethod::Hemisphere,
                rays: 256,
                filter_radius: 0,
                ..Default::default()
            },
            size,
        );
        let (ev, eh) = (mean_difference(&v, &direct), mean_difference(&hemi, &direct));
        println!("{kind}: mean indirect VPL {ev:.4e}, hemisphere {eh:.4e}, ratio {:.3}", ev / eh);
        // Measured ratios 1.024 (point), 0.991 (spot), 0.971 (directional): 64 VPLs × 16 sets
        // against 256 rays per pixel, each a few percent of noise in the mean.
        assert!(eh > 0.0 && (ev / eh - 1.0).abs() < 0.06, "{kind}: VPL {ev} vs hemisphere {eh}");
    }
}

#[test]
fn the_debug_view_draws_first_and_second_bounce_vpls() {
    let scene = load_scene_arg(None).expect("the built-in Cornell box");
    let ctx = common::context();
    let img = render(
        &ctx,
        &scene,
        vpl(VplSettings {
            per_set: 2,
            show: true,
            ..Default::default()
        }),
        64,
    );
    // Dots have radiance 100 (yellow 1,1,0: first bounce; cyan 0,1,1: later), far above the
    // box's own radiance (below 2 everywhere).
    let count = |color: [f32; 3]| img.data.iter().filter(|p| **p == color).count();
    let (first, later) = (count([100.0, 100.0, 0.0]), count([0.0, 100.0, 100.0]));
    println!("dot pixels: {first} first bounce, {later} later");
    assert!(
        first > 0 && later > 0,
        "{first} first-bounce and {later} later dot pixels"
    );
}

/// Emitters send VPLs of their own (`gi_vpl_emit`): the emissive Cornell box has no lights,
/// and with `--gi vpl` the walls, floor and blocks are lit by the emitter's VPLs alone. The
/// area-light scene, which `--gi vpl` refused before, renders validation-clean (`render`
/// checks) and gains light: its indirect light is non-negative and somewhere positive.
#[test]
fn emitters_and_area_lights_send_vpls() {
    let ctx = common::context();
    for (name, emissive_only) in [("cornell_emissive", true), ("area_light", false)] {
        let scene =
            load_scene_arg(Some(&format!("{ROOT}/assets/scenes/{name}.toml"))).expect("loads");
        let none = GiSettings {
            method: GiMethod::None,
            ..Default::default()
        };
        let direct = render(&ctx, &scene, none, 64);
        let lit = render(&ctx, &scene, vpl(VplSettings::default()), 64);
        let (mut dark, mut lit_dark, mut gained) = (0, 0, 0.0f64);
        for (d, l) in direct.data.iter().zip(&lit.data) {
            gained += f64::from(l[0] + l[1] + l[2] - d[0] - d[1] - d[2]);
            if d[..3] == [0.0; 3] {
                dark += 1;
                if l[..3].iter().any(|c| *c > 0.0) {
                    lit_dark += 1;
                }
            }
        }
        println!("{name}: {lit_dark} of {dark} unlit pixels lit by VPLs, gained {gained:.2}");
        assert!(gained > 0.0, "{name}: VPLs add no light");
        if emissive_only {
            // Under --gi vpl the emitter's light reaches the room through its VPLs alone (the
            // direct term of `direct_emitters`, which lights it under --gi none, leaves it to
            // them): the walls, floor and blocks are lit, the copper sphere too since the
            // gather shades GGX receivers with their whole BRDF (measured 94% of the pixels
            // that direct light left black before direct_emitters: 3822 of 4074).
            let lit_by_vpls = lit
                .data
                .iter()
                .filter(|l| l.iter().any(|c| *c > 0.0))
                .count();
            assert!(
                lit_by_vpls * 10 > lit.data.len() * 9,
                "{name}: {lit_by_vpls} of {} pixels lit",
                lit.data.len()
            );
        }
    }
}

/// The emitter table follows the lights (`GiVplEmit::update` from `Renderer::prepare`): one
/// renderer, an area light switched off and then moved, each next frame against a fresh
/// renderer made for the new lights. Before the table followed them, the emitter VPLs of the
/// switched-off light stayed: 2.2% of the switch was still missing a frame later (the sweep's
/// ghost on area_light, 64²). A frame after each change the image must be the fresh one's:
/// residual ≤ 0.5% of the change (the VPL sets depend only on the frame's lights, so the two
/// agree up to rounding), and the moved light's image within relMSE 1e-4 of the fresh one
/// while before the move it is ≥ 10× that far.
#[test]
fn emitter_vpls_follow_lights_that_switch_off_or_move() {
    use voxgi::bench::temporal::{first_light_off, lag_after_switch_off, scene_at_step};
    let scene = Scene::load(Path::new(ROOT).join("assets/scenes/area_light.toml"))
        .expect("area_light.toml");
    let ctx = common::context();
    let settings = RenderSettings {
        width: 64,
        height: 64,
        gi: vpl(VplSettings::default()),
        ..Default::default()
    };
    assert!(first_light_off(&scene).is_some());
    let lag = lag_after_switch_off(&ctx, &scene, &settings, 4)
        .expect("renders")
        .expect("the area light changes the image");
    common::assert_no_validation_messages(&ctx);
    println!("switch-off: {lag:?}");
    assert!(lag.ghost <= 0.005, "{lag:?}");

    let moved = scene_at_step(&scene, 1, 4, 0.3);
    let seq =
        voxgi::render::render_sequence(&ctx, &scene, &settings, 1, std::slice::from_ref(&moved))
            .expect("renders");
    let fresh = render_image(&ctx, &moved, &settings).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    let after = compare(&fresh, &seq.frames[0], None)
        .expect("same size")
        .rel_mse;
    let before = compare(&fresh, &seq.warm, None).expect("same size").rel_mse;
    println!("moved light: relMSE to the fresh image {after} after the move, {before} before");
    assert!(
        after <= 1e-4 && before >= 10.0 * after,
        "{after} vs {before}"
    );
}

/// The same for an emissive object that moves (its keyframes, scene time 0 → 1): one renderer
/// re-voxelizes it and rebuilds the emitter table at the new time; the frame after the move
/// must be a fresh renderer's at that time (relMSE ≤ 1e-4), while the frame before it is far
/// from it.
#[test]
fn emitter_vpls_follow_a_moving_emissive_object() {
    use voxgi::graph::{run_frames, GraphExecutor};
    let mover = include_str!("../assets/scenes/cornell_mover.toml").replace(
        "builtin = \"cube\"\nscale = 0.12",
        "builtin = \"cube\"\nscale = 0.12\nmaterial = { albedo = 0.5, emission_w_sr_m2 = [20.0, 20.0, 20.0] }",
    );
    assert!(
        mover.contains("emission_w_sr_m2"),
        "the mover became emissive"
    );
    let scene = Scene::from_toml_str(&mover, Path::new("mover.toml"), Path::new(ROOT))
        .expect("scene parses");
    let ctx = common::context();
    let at = |t_s| RenderSettings {
        width: 64,
        height: 64,
        time_s: t_s,
        gi: vpl(VplSettings::default()),
        ..Default::default()
    };
    let mut r = voxgi::render::Renderer::new(&ctx, &scene, at(0.0)).expect("renderer");
    let exec = GraphExecutor::new(&ctx, r.graph(), voxgi::vk::MAX_FRAMES_IN_FLIGHT).expect("graph");
    run_frames(&ctx, &exec, 1, 0, |slot| r.write_frame(slot)).expect("frame at t = 0");
    let before = r.hdr_image();
    r.settings.time_s = 1.0;
    r.prepare(&scene).expect("prepares");
    run_frames(&ctx, &exec, 1, 0, |slot| r.write_frame(slot)).expect("frame at t = 1");
    let after = r.hdr_image();
    drop(exec);
    drop(r);
    let fresh = render_image(&ctx, &scene, &at(1.0)).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    let m_after = compare(&fresh, &after, None).expect("same size").rel_mse;
    let m_before = compare(&fresh, &before, None).expect("same size").rel_mse;
    println!("moving emitter: relMSE to the fresh image {m_after} after, {m_before} before");
    assert!(
        m_after <= 1e-4 && m_before >= 10.0 * m_after.max(1e-5),
        "{m_after} vs {m_before}"
    );
}

/// A white metal plate (F0 = 1, r = 0.8, m = 1) at the bottom of a closed Lambert sphere of
/// radius 1 m and albedo 0.5, lit by a narrow spot (5°, fully on the plate, falloff 1) from
/// 0.8 m above it; the camera inside looks at the sphere's side.
const METAL_FURNACE: &str = r#"
[camera]
position = [0.0, 0.2, 0.0]
target = [0.0, 0.2, 1.0]
fov_y_deg = 30.0
near = 0.01
far = 10.0
[[lights]]
kind = "spot"
position = [0.0, 0.3, 0.0]
direction = [0.0, -1.0, 0.0]
intensity_w_sr = 100.0
cutoff_deg = 5.0
beam_deg = 5.0
[[objects]]
name = "sphere"
builtin = "sphere"
scale = 2.0
material = { albedo = 0.5 }
[[objects]]
name = "plate"
builtin = "quad"
translate = [0.0, -0.5, 0.0]
scale = 0.3
material = { albedo = 1.0, roughness = 0.8, metallic = 1.0 }
"#;

/// Directional albedo of the metal plate's GGX lobe at incidence θ (from its normal):
/// A(θ) = ∫ f(wi, wo) cos θ_o dω_o, the fraction of the incident flux it reflects, by the
/// midpoint rule on 400 × 400 cells in (cos θ_o, φ_o) (dω = d cos θ dφ). Below 1: single-
/// scattering GGX loses the light that would scatter again between microfacets.
fn metal_albedo(theta: f32, g: voxgi::scene::Ggx) -> f32 {
    let wi = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let n = 400;
    let mut sum = 0.0f64;
    for i in 0..n {
        let c = (i as f32 + 0.5) / n as f32;
        let s = (1.0 - c * c).sqrt();
        for k in 0..n {
            let phi = (k as f32 + 0.5) / n as f32 * 2.0 * std::f32::consts::PI;
            let wo = Vec3::new(s * phi.cos(), c, s * phi.sin());
            let f = voxgi::scene::ggx_brdf(Vec3::ONE, g, Vec3::Y, wi, wo).x;
            sum += f64::from(f * c);
        }
    }
    (sum * 2.0 * std::f64::consts::PI / (n * n) as f64) as f32
}

/// Energy of a metal sender's VPLs (a white-furnace-like check): the spot's flux
/// Φ = I·2π(1 − cos 5°) all reaches the plate, whose GGX VPLs carry Φ_in (K per set sharing
/// it); the second bounce samples their lobe (`gi_vpl_bounce`, weight F·G1 for visible
/// normals, F = 1 here) and leaves flux Φ·A on the sphere, A the plate's directional albedo
/// (0.555 at r = 0.8, [`metal_albedo`]). In a sphere, a Lambert VPL of flux Φ_v at y gives every
/// point x of the inside the same irradiance: cos θ_y = cos θ_x = d/(2R), so
/// E = Φ_v/π · cos θ_y cos θ_x / d² = Φ_v/(4πR²). So the second bounce alone (the render with
/// two bounces minus the one with one, same first-bounce VPLs; no visibility test and no
/// d_min, as in the furnace of tests/gi.rs) is L = ρ/π · ρ Σ Φ_out/(4πR²) everywhere, and
/// its ratio to ρ²Φ/(4π²R²) measures Σ Φ_out/Φ: it must not exceed 1 (the VPLs carry no
/// more than the light's flux) and must equal A within 4% (measured 0.561 against 0.555: the
/// voxel hits lie up to a voxel off the tessellated sphere, with voxel normals, and 1024 lobe
/// samples leave about 1% of noise).
#[test]
fn metal_vpls_carry_no_more_than_the_lights_flux() {
    let scene = scene_from(METAL_FURNACE);
    let ctx = common::context();
    let size = 32;
    let settings = |bounces| GiSettings {
        filter_radius: 0,
        ..vpl(VplSettings {
            per_set: 64,
            bounces,
            d_min_voxels: 0.0,
            visibility: VplVisibility::None,
            ..Default::default()
        })
    };
    let one = render(&ctx, &scene, settings(1), size);
    let two = render(&ctx, &scene, settings(2), size);
    // The central 8×8 window: every one of the 4×4 sets four times.
    let mut second = 0.0f64;
    for y in 12..20 {
        for x in 12..20 {
            let i = (y * size + x) as usize;
            second += f64::from(two.data[i][0] - one.data[i][0]) / 64.0;
        }
    }
    let pi = std::f64::consts::PI;
    let (rho, radius) = (0.5f64, 1.0f64);
    let flux = 100.0 * 2.0 * pi * (1.0 - 5.0f64.to_radians().cos());
    let full = rho / pi * rho * flux / (4.0 * pi * radius * radius);
    let ratio = (second / full) as f32;
    let g = voxgi::scene::Ggx {
        roughness: 0.8,
        metallic: 1.0,
    };
    // The spot's rays meet the plate within 5° of its normal.
    let (a0, a5) = (metal_albedo(0.0, g), metal_albedo(5.0f32.to_radians(), g));
    println!("metal furnace: second bounce {second:.5} W/(m² sr), {ratio:.4} of the light's flux; A(0°) {a0:.4}, A(5°) {a5:.4}");
    assert!((a0 - a5).abs() < 0.002, "A(0°) {a0} vs A(5°) {a5}");
    assert!(
        ratio <= 1.0,
        "the metal's VPLs carry {ratio} of the light's flux"
    );
    assert!(
        (ratio - a0).abs() < 0.04 * a0,
        "second-bounce flux {ratio} of Φ vs the plate's albedo {a0}"
    );
}

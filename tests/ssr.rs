//! Screen-space reflections of `--gi ssgi` (Oetke 2017 §5.4): a smooth metal floor under an
//! emissive box reflects the box's lit colour times the split-sum directional albedo; rays
//! that leave the screen give exactly the diffuse fallback; `--ssr off` and scenes without
//! glossy materials have no reflection passes; rough floors read coarser mips of the colour
//! pyramid. No lights: the emitters are the only light, so every lit colour is known exactly.
//! Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::HdrImage;
use voxgi::gi::{GiMethod, GiSettings, SsgiSettings, SsrRays};
use voxgi::render::RenderOutput;
use voxgi::scene::Scene;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The emitter's radiance, W/(m² sr): exact in 16-bit floats.
const EMISSION: [f32; 3] = [2.0, 1.0, 0.5];
/// The metal floor's base color = F0 (metallic 1): exact in the G-buffer's 16-bit floats to
/// 2.5e-4 relative.
const F0: [f32; 3] = [0.8, 0.6, 0.2];
/// The camera, looking down at the floor in front of the box.
const CAMERA: Vec3 = Vec3::new(0.0, 1.0, -2.5);

/// A 6 m metal floor at y = 0 with the given roughness and `boxes` (TOML object tables); no
/// lights, 50° field of view.
fn scene(roughness: f32, boxes: &str) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [{}, {}, {}]
target = [0.0, 0.0, 0.5]
fov_y_deg = 50.0
near = 0.01
far = 20.0
[[objects]]
builtin = "quad"
scale = [6.0, 1.0, 6.0]
material = {{ albedo = [{}, {}, {}], roughness = {roughness}, metallic = 1.0 }}
{boxes}
"#,
        CAMERA.x, CAMERA.y, CAMERA.z, F0[0], F0[1], F0[2]
    );
    Scene::from_toml_str(&toml, Path::new("<ssr scene>"), Path::new(ROOT)).expect("parses")
}

/// An emissive, otherwise black unit cube, front face at z = 0.5, x and y in [−0.5, 0.5] and
/// [0, 1].
fn emissive_box() -> String {
    let [r, g, b] = EMISSION;
    format!(
        "[[objects]]\nbuiltin = \"cube\"\ntranslate = [0.0, 0.5, 1.0]\n\
         material = {{ albedo = 0.0, emission_w_sr_m2 = [{r}, {g}, {b}] }}\n"
    )
}

/// `--gi ssgi` with reflections on or off, 2 frames, no geometry-aware filter (it would
/// blur the indirect light across the reflection's edges).
fn gi(ssr: bool) -> GiSettings {
    GiSettings {
        method: GiMethod::Ssgi,
        accumulate_frames: 2,
        filter_radius: 0,
        ssgi: SsgiSettings {
            ssr,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn render(scene: &Scene, size: u32, gi: GiSettings) -> RenderOutput {
    common::render_with_gi(scene, size, gi)
}

fn has_reflection_passes(out: &RenderOutput) -> bool {
    out.live_passes
        .iter()
        .any(|p| p.starts_with("ssgi_reflect"))
}

/// Where pixel (x, y)'s view ray meets the floor (y = 0), if it does in front of the box.
fn floor_point(scene: &Scene, x: u32, y: u32, size: u32) -> Option<Vec3> {
    let (near, far) = scene.camera.pixel_ray_points(x, y, size, size);
    let d = far - near;
    if d.y >= 0.0 {
        return None;
    }
    let p = near + d * (-near.y / d.y);
    (p.z < 0.4 && p.x.abs() < 3.0).then_some(p)
}

/// The mirror ray from floor point `p` seen from the camera: (x, y) where it crosses the
/// plane z = `z`.
fn mirror_at_z(p: Vec3, z: f32) -> (f32, f32) {
    let v = (CAMERA - p).normalize();
    let r = Vec3::new(-v.x, v.y, -v.z);
    let t = (z - p.z) / r.z;
    (p.x + t * r.x, p.y + t * r.y)
}

/// The mirror ray from pixel (x, y)'s floor point hits the box's front face at least 0.15 m
/// inside its edges (so the 3×3 blur's neighbours hit it too).
fn hits_box_face(scene: &Scene, x: u32, y: u32, size: u32) -> Option<Vec3> {
    let p = floor_point(scene, x, y, size)?;
    let (hx, hy) = mirror_at_z(p, 0.5);
    (hx.abs() < 0.35 && (0.15..0.85).contains(&hy)).then_some(p)
}

fn pixel(img: &HdrImage, x: u32, y: u32) -> [f32; 3] {
    img.data[(y * img.width + x) as usize]
}

/// (a) A near-mirror metal floor (roughness 0.05, α = 0.0025) reflects the emissive box: at
/// every floor pixel whose mirror ray hits the box's front face well inside its edges, the
/// radiance is L_e·(F0·A + B) (Eq. 2.19 with the diffuse colour (1 − m)·b = 0, no direct light:
/// no lights), A and B the split-sum table at the pixel's (n·v, roughness) texel, read back
/// from the GPU (the table itself is checked against a CPU quadrature in tests/ssgi.rs).
/// The reflected colour is exactly L_e: the box's lit colour is its emission (black albedo
/// receives nothing) and the lobe's cone is far below a pixel (level 0). Bound: the expected
/// value is taken over the table's n·v texels i − 1..=i + 1 (the shader's n·v comes from the
/// reconstructed position, which may round across a texel edge), with 0.5% for the 16-bit
/// colour pyramid and G-buffer (2⁻¹¹ relative each) and the F0 in 16 bits.
/// Also, as α → 0, F0·A + B tends to Schlick's F(n·v) (D integrates to 1, G1 → 1): the
/// table at these texels is within 2% of it (the 1024 Hammersley samples of a near-delta lobe
/// are all near the mirror direction).
#[test]
fn a_mirror_floor_reflects_the_box_times_the_split_sum_albedo() {
    use voxgi::gi::ssgi_brdf_lut::{BrdfLut, LUT_SIZE};
    const SIZE: u32 = 64;
    const ROUGHNESS: f32 = 0.05;
    let scene = scene(ROUGHNESS, &emissive_box());
    let out = render(&scene, SIZE, gi(true));
    assert!(has_reflection_passes(&out));
    let ctx = common::context();
    let table = BrdfLut::new(&ctx).expect("lut").read(&ctx).expect("reads");
    common::assert_no_validation_messages(&ctx);
    let row = (ROUGHNESS * LUT_SIZE as f32) as u32;
    let mut checked = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = hits_box_face(&scene, x, y, SIZE) else {
                continue;
            };
            let n_dot_v = (CAMERA - p).normalize().y;
            let i = ((n_dot_v * LUT_SIZE as f32) as u32).min(LUT_SIZE - 1);
            let got = pixel(&out.hdr, x, y);
            for c in 0..3 {
                let albedo = |i: u32| {
                    let [a, b] = table[(row * LUT_SIZE + i.min(LUT_SIZE - 1)) as usize];
                    F0[c] * a + b
                };
                let range = [i.saturating_sub(1), i, i + 1].map(albedo);
                let lo = range.iter().cloned().fold(f32::MAX, f32::min) * EMISSION[c] * 0.995;
                let hi = range.iter().cloned().fold(0.0, f32::max) * EMISSION[c] * 1.005;
                assert!(
                    (lo..=hi).contains(&got[c]),
                    "pixel ({x}, {y}) channel {c}: {} not in [{lo}, {hi}] (n·v {n_dot_v})",
                    got[c]
                );
                let schlick = F0[c] + (1.0 - F0[c]) * (1.0 - n_dot_v).powi(5);
                assert!(
                    (albedo(i) - schlick).abs() < 0.02 * schlick,
                    "table {} vs Schlick {schlick} at n·v {n_dot_v}",
                    albedo(i)
                );
            }
            checked += 1;
        }
    }
    println!("mirror floor: {checked} pixels reflect the box");
    assert!(checked >= 20, "only {checked} pixels reflect the box");
}

/// (b) Floor pixels whose mirror rays (and their 3×3 neighbours') pass the box at least
/// 0.2 m to its side rise over the floor and leave the screen without a hit: confidence 0, so
/// L_spec is exactly the diffuse fallback E/π and the pixel equals the `--ssr off` image bit
/// for bit (the reflections change nothing the diffuse gather reads). No pixel is NaN or
/// infinite.
#[test]
fn rays_leaving_the_screen_fall_back_to_the_diffuse_light() {
    const SIZE: u32 = 64;
    let scene = scene(0.05, &emissive_box());
    let on = render(&scene, SIZE, gi(true)).hdr;
    let off = render(&scene, SIZE, gi(false)).hdr;
    assert!(
        on.data.iter().flatten().all(|v| v.is_finite()),
        "NaN or infinity"
    );
    let misses = |x: u32, y: u32| {
        floor_point(&scene, x, y, SIZE).is_some_and(|p| {
            // Past the box's side over its whole depth (z from 0.5 to 1.5).
            let (a, _) = mirror_at_z(p, 0.5);
            let (b, _) = mirror_at_z(p, 1.5);
            a.abs() > 0.7 && b.abs() > 0.7 && a.signum() == b.signum()
        })
    };
    let mut checked = 0;
    for y in 1..SIZE - 1 {
        for x in 1..SIZE - 1 {
            let all = (0..9).all(|k| misses(x + k % 3 - 1, y + k / 3 - 1));
            if !all {
                continue;
            }
            let (a, b) = (pixel(&on, x, y), pixel(&off, x, y));
            assert_eq!(a, b, "pixel ({x}, {y})");
            assert!(b[0] > 0.0, "the fallback is lit: pixel ({x}, {y})");
            checked += 1;
        }
    }
    println!("off-screen rays: {checked} pixels equal the fallback");
    assert!(checked >= 50, "only {checked} pixels checked");
}

/// (c) `--ssr off` has no reflection pass (and so none of their images), nor has a scene
/// without Phong or GGX materials with reflections on, whose image is then bit-identical to
/// the one with them off.
#[test]
fn without_reflections_nothing_is_declared() {
    const SIZE: u32 = 32;
    let glossy = scene(0.05, &emissive_box());
    assert!(!has_reflection_passes(&render(&glossy, SIZE, gi(false))));
    let lambert_text =
        "[camera]\nposition = [0.0, 1.0, -2.5]\ntarget = [0.0, 0.0, 0.5]\nfov_y_deg = 50.0\n\
        [[objects]]\nbuiltin = \"quad\"\nscale = [6.0, 1.0, 6.0]\n\
        material = { albedo = 0.5 }\n"
            .to_owned()
            + &emissive_box();
    let lambert =
        Scene::from_toml_str(&lambert_text, Path::new("<lambert>"), Path::new(ROOT)).unwrap();
    let on = render(&lambert, SIZE, gi(true));
    let off = render(&lambert, SIZE, gi(false));
    assert!(!has_reflection_passes(&on));
    assert_eq!(on.hdr.data, off.hdr.data);
}

/// Three emissive bars in front of the floor's far end, 0.3 m wide with 0.3 m gaps, before a
/// black wall at z = 1.6 facing the camera (so that rays through the gaps hit something and
/// read the colour pyramid too: a single mirror ray's hit-or-miss mask is never blurred).
fn bars() -> String {
    let wall = "[[objects]]\nbuiltin = \"quad\"\ntranslate = [0.0, 1.5, 1.6]\n\
        rotate_deg = [-90.0, 0.0, 0.0]\nscale = [6.0, 1.0, 3.0]\nmaterial = { albedo = 0.0 }\n";
    [-0.6f32, 0.0, 0.6]
        .iter()
        .map(|x| {
            format!(
                "[[objects]]\nbuiltin = \"cube\"\ntranslate = [{x}, 0.5, 1.0]\n\
                 scale = [0.3, 1.0, 0.3]\n\
                 material = {{ albedo = 0.0, emission_w_sr_m2 = 2.0 }}\n"
            )
        })
        .chain(std::iter::once(wall.to_owned()))
        .collect()
}

/// The mean over image rows of the coefficient of variation (std / mean) of the red radiance
/// across the row's floor pixels whose mirror rays cross the bars' plane (z = 0.85) at
/// heights 0.3 to 0.7 and |x| < 0.9: the stripes' contrast, without the vertical gradient of
/// the split-sum factor and the cone's level.
fn reflection_contrast(scene: &Scene, img: &HdrImage) -> f32 {
    let mut rows = Vec::new();
    for y in 0..img.height {
        let mut v = Vec::new();
        for x in 0..img.width {
            let Some(p) = floor_point(scene, x, y, img.width) else {
                continue;
            };
            let (hx, hy) = mirror_at_z(p, 0.85);
            if hx.abs() < 0.9 && (0.3..0.7).contains(&hy) {
                v.push(pixel(img, x, y)[0]);
            }
        }
        if v.len() >= 40 {
            let mean = v.iter().sum::<f32>() / v.len() as f32;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / v.len() as f32;
            rows.push(var.sqrt() / mean);
        }
    }
    assert!(rows.len() >= 5, "{} rows", rows.len());
    rows.iter().sum::<f32>() / rows.len() as f32
}

/// (d) A rougher floor reads coarser levels of the colour pyramid, so the bars' reflection
/// loses contrast. At 128², 50° and about 3.2 m from the camera a bar and a gap are 13 px
/// each, a 26-px square wave. Roughness 0.02 gives a cone of tan θ ≈ 7e-5: level 0, the
/// stripes stay sharp. Roughness 0.35 (α = 0.1225, Phong-equivalent n ≈ 131, cos θ =
/// 2^(−1/n), tan θ ≈ 0.10) over the 1.2–1.8 m to the bars gives footprints of 4–8 px:
/// levels 2–3, whose box-filtered texels read bilinearly remove the square wave's harmonics
/// (19% of its variance, 1 − 8/π²) and damp its fundamental at least by sinc(6/26)·sinc²(6/26)
/// ≈ 0.77 in amplitude, so the standard deviation falls to at most √0.81·0.77 ≈ 0.70 of the
/// sharp one's (the split-sum factor and the fallback are smooth across the stripes). Bound:
/// the rough contrast is below 0.75 of the smooth one's.
#[test]
fn rough_floors_reflect_blurrier() {
    const SIZE: u32 = 128;
    let smooth_scene = scene(0.02, &bars());
    let rough_scene = scene(0.35, &bars());
    let smooth = reflection_contrast(&smooth_scene, &render(&smooth_scene, SIZE, gi(true)).hdr);
    let rough = reflection_contrast(&rough_scene, &render(&rough_scene, SIZE, gi(true)).hdr);
    println!("reflection contrast: roughness 0.02 {smooth:.3}, 0.35 {rough:.3}");
    assert!(rough < 0.75 * smooth, "{rough} vs {smooth}");
}

/// `--gi ssgi` with reflections by `rays`, `frames` frames, no geometry-aware filter.
fn gi_rays(rays: SsrRays, frames: u32) -> GiSettings {
    GiSettings {
        accumulate_frames: frames,
        ssgi: SsgiSettings {
            ssr_rays: rays,
            ..Default::default()
        },
        ..gi(true)
    }
}

/// The metal floor's reflection of the emissive box's front face (z = 0.5, x in [−0.5, 0.5],
/// y in [0, 1], facing −z) at floor point `p`, seen from the camera: ∫ f_spec L_e (n·l) dl
/// over the face, by the midpoint rule on `cells`² patches, each subtending
/// dA·cos θ_face / d² (exact GGX BRDF of `scene::ggx_specular`, metal: F0 = base color).
/// From a floor point with |x| < 0.5 in front of the box no other face of the box is
/// visible (the side faces face away, the top one faces up), and with no lights and a black
/// sky the face's emission is all the floor reflects: this is the true radiance.
fn face_reflection(p: Vec3, roughness: f32, cells: u32) -> [f32; 3] {
    let wo = (CAMERA - p).normalize();
    let n = Vec3::Y;
    let f0 = Vec3::from(F0);
    let da = 1.0 / (cells * cells) as f32;
    let mut sum = Vec3::ZERO;
    for j in 0..cells {
        for i in 0..cells {
            let q = Vec3::new(
                -0.5 + (i as f32 + 0.5) / cells as f32,
                (j as f32 + 0.5) / cells as f32,
                0.5,
            );
            let d = q - p;
            let d2 = d.length_squared();
            let wi = d / d2.sqrt();
            let f = voxgi::scene::ggx_specular(f0, roughness, n, wi, wo);
            sum += f * (wi.y * wi.z * da / d2);
        }
    }
    let e = Vec3::from(EMISSION);
    (sum * e).to_array()
}

/// relMSE (ε = 1e-2, voxgi's definition) of `img` against `reference` over `pixels`.
fn rel_mse(img: &HdrImage, pixels: &[((u32, u32), [f32; 3])]) -> f64 {
    let mut sum = 0.0f64;
    for &((x, y), r) in pixels {
        let got = pixel(img, x, y);
        for c in 0..3 {
            let d = f64::from(got[c] - r[c]);
            sum += d * d / (f64::from(r[c]).powi(2) + 1e-2);
        }
    }
    sum / (3 * pixels.len()) as f64
}

/// (e) Lobe-sampled rays converge to the rough floor's true glossy reflection better than
/// the mirror ray with its cone's mip. Floor roughness 0.3 (α = 0.09) under the emissive box,
/// 64², 16 frames each way; the reference is the exact reflection of the box's face
/// ([`face_reflection`], 160² patches) at every floor pixel in front of the box (|x| < 0.4,
/// z < 0.3) that reflects at least 0.05 W/(m² sr) of red. The mirror ray decides hit or miss
/// by one direction, so near the reflection's top edge it is all box or all fallback where
/// the lobe straddles the edge; the lobe samples average the straddling lobe. Measured:
/// mirror 0.106, lobe 0.014 (one lobe frame alone: 0.23, worse than the mirror); bound: the
/// lobe below half the mirror's relMSE.
#[test]
fn lobe_sampled_rays_converge_to_the_glossy_reflection() {
    const SIZE: u32 = 64;
    const ROUGHNESS: f32 = 0.3;
    const FRAMES: u32 = 16;
    let scene = scene(ROUGHNESS, &emissive_box());
    let mut pixels = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = floor_point(&scene, x, y, SIZE) else {
                continue;
            };
            if p.x.abs() >= 0.4 || p.z >= 0.3 {
                continue;
            }
            let r = face_reflection(p, ROUGHNESS, 160);
            if r[0] >= 0.05 {
                pixels.push(((x, y), r));
            }
        }
    }
    let mirror = render(&scene, SIZE, gi_rays(SsrRays::Mirror, FRAMES)).hdr;
    let lobe = render(&scene, SIZE, gi_rays(SsrRays::Lobe, FRAMES)).hdr;
    let e_mirror = rel_mse(&mirror, &pixels);
    let e_lobe = rel_mse(&lobe, &pixels);
    let one = rel_mse(
        &render(&scene, SIZE, gi_rays(SsrRays::Lobe, 1)).hdr,
        &pixels,
    );
    println!(
        "rough floor reflection, {} pixels, relMSE at {FRAMES} frames: mirror {e_mirror:.4}, \
         lobe {e_lobe:.4} (lobe after 1 frame {one:.4})",
        pixels.len()
    );
    assert!(pixels.len() >= 100, "only {} pixels", pixels.len());
    assert!(
        e_lobe < 0.5 * e_mirror,
        "lobe {e_lobe} vs mirror {e_mirror}"
    );
}

/// (f) A mirror floor (roughness 0) has a lobe narrower than a pixel: lobe sampling keeps the
/// mirror ray, and the image is bit-identical to the mirror choice's.
#[test]
fn a_mirror_floor_is_the_same_with_either_ray_choice() {
    const SIZE: u32 = 48;
    let scene = scene(0.0, &emissive_box());
    let mirror = render(&scene, SIZE, gi_rays(SsrRays::Mirror, 3)).hdr;
    let lobe = render(&scene, SIZE, gi_rays(SsrRays::Lobe, 3)).hdr;
    assert!(
        mirror.data.iter().flatten().any(|&v| v > 0.5),
        "the floor reflects the box"
    );
    assert_eq!(mirror.data, lobe.data);
}

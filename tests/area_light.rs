//! Area lights rendered as sums of sampled sub-lights (`voxgi::light::area`): the penumbra
//! behind a straight edge against similar triangles, and convergence to the Mitsuba 3
//! direct-light reference of `assets/scenes/area_light.toml` as the sample count grows.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::light::area::{grid_for, sample_lights};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{Light, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn render(scene: &Scene, settings: &RenderSettings) -> HdrImage {
    let ctx = common::context();
    let out = render_image(&ctx, scene, settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    out.hdr
}

// The penumbra scenes: a floor at y = 0, a plate over x < 0, 0 < z < 2 at height H_B (0.02 m
// thick), and an area light centred at height H above (0, z = 1). The floor's profile across
// the plate's edge (along x at z = 1) is read from the image; the camera is below the plate,
// so it sees the floor under it.
const H: f32 = 2.0;
const H_B: f32 = 0.5;

fn penumbra_scene(light: &str) -> Scene {
    let toml = format!(
        "[camera]\nposition = [0, 0.3, -0.5]\ntarget = [0, 0, 1]\nfov_y_deg = 30\n\
         [[lights]]\n{light}\n\
         [[objects]]\nbuiltin = \"quad\"\nscale = [4, 1, 4]\n\
         [[objects]]\nbuiltin = \"cube\"\ntranslate = [-1, {H_B}, 1]\nscale = [2, 0.02, 2]\n"
    );
    Scene::from_toml_str(&toml, Path::new("penumbra.toml"), Path::new(ROOT)).expect("scene")
}

/// The floor's radiance along world x (z = 1) from `x0` to `x1` in 1 mm steps, read from the
/// image by projecting each floor point and interpolating between the two nearest pixels.
fn floor_profile(img: &HdrImage, scene: &Scene, x0: f32, x1: f32) -> Vec<(f32, f32)> {
    let vp = scene.camera.view_proj(img.width as f32 / img.height as f32);
    let steps = ((x1 - x0) / 1e-3).round() as usize;
    (0..=steps)
        .map(|i| {
            let x = x0 + i as f32 * 1e-3;
            let ndc = vp.project_point3(Vec3::new(x, 0.0, 1.0));
            let fx = (ndc.x * 0.5 + 0.5) * img.width as f32 - 0.5;
            let row =
                (((ndc.y * 0.5 + 0.5) * img.height as f32) as usize).min(img.height as usize - 1);
            let c = (fx.floor() as usize).min(img.width as usize - 2);
            let t = (fx - c as f32).clamp(0.0, 1.0);
            let at = |col: usize| img.data[row * img.width as usize + col][1];
            (x, at(c) * (1.0 - t) + at(c + 1) * t)
        })
        .collect()
}

/// The same profile predicted from the light's samples by similar triangles: the sample at
/// P casts the edge (x = 0, y = H_B) onto the floor at x_i = −P.x·H_B/(P.y − H_B) and lights
/// the floor beyond it, with the weight I·cos θ_e·cos θ_r/d² it has at the penumbra's
/// centre (0, 0, 1) (nearly constant across the few centimeters of penumbra).
fn predicted_profile(lights: &[Light], x0: f32, x1: f32) -> Vec<(f32, f32)> {
    let q = Vec3::new(0.0, 0.0, 1.0);
    let edges: Vec<(f32, f32)> = lights
        .iter()
        .map(|l| {
            let Light::Element {
                position: p,
                normal,
                intensity_w_sr,
                ..
            } = *l
            else {
                panic!("only samples")
            };
            let d = q - p;
            let w = d.normalize();
            let weight =
                intensity_w_sr.y * normal.dot(w).max(0.0) * (-w.y).max(0.0) / d.length_squared();
            (-p.x * H_B / (p.y - H_B), weight)
        })
        .collect();
    let steps = ((x1 - x0) / 1e-4).round() as usize;
    (0..=steps)
        .map(|i| {
            let x = x0 + i as f32 * 1e-4;
            let lit: f32 = edges.iter().filter(|e| e.0 < x).map(|e| e.1).sum();
            (x, lit)
        })
        .collect()
}

/// The first x where the (increasing) `profile`, scaled from `lo` to `hi`, reaches `level`.
fn crossing(profile: &[(f32, f32)], lo: f32, hi: f32, level: f32) -> f32 {
    let v = |i: usize| (profile[i].1 - lo) / (hi - lo);
    for i in 1..profile.len() {
        if v(i) >= level {
            let t = (level - v(i - 1)) / (v(i) - v(i - 1)).max(1e-9);
            return profile[i - 1].0 + t.clamp(0.0, 1.0) * (profile[i].0 - profile[i - 1].0);
        }
    }
    panic!("the profile never reaches {level}");
}

/// The 10% and 90% crossings of a profile between its plateaus at |x| >= 0.15 m.
fn ten_ninety(profile: &[(f32, f32)]) -> (f32, f32) {
    let mean = |a: f32, b: f32| {
        let v: Vec<f32> = profile
            .iter()
            .filter(|(x, _)| (a..=b).contains(x))
            .map(|p| p.1)
            .collect();
        v.iter().sum::<f32>() / v.len() as f32
    };
    let (lo, hi) = (mean(-0.3, -0.15), mean(0.15, 0.3));
    assert!(lo < 0.02 * hi, "umbra {lo} vs lit {hi}");
    (
        crossing(profile, lo, hi, 0.1),
        crossing(profile, lo, hi, 0.9),
    )
}

/// Renders the penumbra scene with `light` and checks the 10%–90% width and centre of the
/// penumbra against the similar-triangles prediction from the light's samples. Returns the
/// measured width.
fn check_penumbra(light: &str, samples: u32) -> f32 {
    let scene = penumbra_scene(light);
    let mut settings = RenderSettings {
        width: 256,
        height: 128,
        ..Default::default()
    };
    settings.shadow.area_samples = Some(samples);
    let img = render(&scene, &settings);
    let (x10, x90) = ten_ninety(&floor_profile(&img, &scene, -0.3, 0.3));
    let lights = sample_lights(&scene.lights, Some(samples));
    let (p10, p90) = ten_ninety(&predicted_profile(&lights, -0.3, 0.3));
    // Tolerance per crossing: a pixel (6.4 mm: 2 tan 15° per 128 rows at the 1.53 m from the
    // camera to (0, 0, 1)), the 3×3 PCF kernel's half-width (1.5 texels of at most 4/1024 rad
    // at the axis of a paraboloid map, at the blocker's 1.5 m, times H/(H − H_B) onto the
    // floor: 11.7 mm) and the plate's thickness (±0.01 m of H_B: ±2% of every x_i, 1.3 mm at
    // the 0.067 m edge of the penumbra).
    let px_m = 2.0 * 0.3f32.hypot(1.5) * 15f32.to_radians().tan() / 128.0;
    let pcf_m = 1.5 * 4.0 / 1024.0 * (H - H_B) * H / (H - H_B);
    let tol = px_m + pcf_m + 0.0013;
    println!(
        "{light:?}: 10%-90% penumbra measured [{x10:.4}, {x90:.4}] m, predicted [{p10:.4}, \
         {p90:.4}] m, +- {tol:.4} each"
    );
    assert!(
        (x10 - p10).abs() <= tol && (x90 - p90).abs() <= tol,
        "penumbra [{x10}, {x90}] m, predicted [{p10}, {p90}] m +- {tol}"
    );
    x90 - x10
}

#[test]
fn rectangle_penumbra_behind_an_edge_matches_similar_triangles() {
    // 0.4 m wide along x, 2.5 cm along z: 16 samples in a row (grid_for).
    let s_m = 0.4;
    let light = format!(
        "kind = \"rectangle\"\nposition = [0, {H}, 1]\nnormal = [0, -1, 0]\n\
         width_axis = [1, 0, 0]\nwidth_m = {s_m}\nheight_m = 0.025\nradiance_w_sr_m2 = 100"
    );
    assert_eq!(grid_for(16, s_m / 0.025), (16, 1));
    let width = check_penumbra(&light, 16);
    // The continuous light: the penumbra w = s (d_r − d_b)/d_b = s H_B/(H − H_B) = 0.133 m
    // (d_r = H, d_b = H − H_B), across which the visible part of the rectangle grows
    // linearly, so its 10%–90% part is 0.8 w = 0.107 m; 16 samples make 16 equal steps and
    // cross 10% and 90% at the 2nd and 15th, 13/16 w = 0.108 m apart.
    let w = s_m * H_B / (H - H_B);
    assert!(
        (width - 0.8 * w).abs() < 0.1 * w,
        "{width} m vs {}",
        0.8 * w
    );
}

#[test]
fn sphere_penumbra_behind_an_edge_matches_similar_triangles() {
    let r_m = 0.2;
    let light = format!(
        "kind = \"sphere\"\nposition = [0, {H}, 1]\nradius_m = {r_m}\nradiance_w_sr_m2 = 50"
    );
    let width = check_penumbra(&light, 48);
    // The continuous sphere looks like a disk of radius R from the floor: behind the edge its
    // visible fraction is the circular segment F(u) = (acos(−u) + u √(1 − u²))/π, u the
    // edge's offset in radii, which crosses 0.1 and 0.9 at u = ∓0.687: the 10%–90% width is
    // 1.374 R·H_B/(H − H_B) = 0.092 m (similar triangles, as for the rectangle). The 48
    // elements facing every way approximate that disk's projection within 15%.
    let continuous = 1.374 * r_m * H_B / (H - H_B);
    assert!(
        (width - continuous).abs() < 0.15 * continuous,
        "{width} m vs {continuous} m"
    );
}

fn area_light_scene() -> Scene {
    Scene::load(Path::new(ROOT).join("assets/scenes/area_light.toml")).expect("area_light.toml")
}

fn reference(mode: &str) -> HdrImage {
    let path = Path::new(ROOT).join(format!("assets/references/area_light_{mode}.exr"));
    HdrImage::load(&path).unwrap_or_else(|e| panic!("reference {}: {e}", path.display()))
}

#[test]
fn sampled_area_lights_converge_to_the_mitsuba_reference() {
    let scene = area_light_scene();
    let direct = reference("direct");
    let mut last = f64::INFINITY;
    for s in [1, 4, 16] {
        let mut settings = RenderSettings {
            width: 256,
            height: 256,
            ..Default::default()
        };
        settings.shadow.area_samples = Some(s);
        let m = compare(&direct, &render(&scene, &settings), None).expect("same size");
        println!("{s} samples per area light: {m:?}");
        assert!(
            m.rel_mse < last,
            "{s} samples: relMSE {} not below {last}",
            m.rel_mse
        );
        last = m.rel_mse;
    }
    // Measured (lavapipe, 256², 1024² shadow maps): relMSE 0.0132 (S = 1), 0.0018 (4),
    // 0.00105 (16), 0.00102 (32): the floor is the edge residue of every direct-light
    // reference (pixel-centre shading vs Mitsuba's box-filtered pixels; 0.00093 on
    // point_light). Bound: twice the S = 16 value, as tests/reference.rs.
    assert!(last < 0.0021, "16 samples: relMSE {last}");
}

/// Area lights feed the GI methods as their samples: the path tracer's direct light at every
/// hit reads the samples' paraboloid shadow maps, the hemisphere method their reflective light
/// maps (drawn through the same paraboloid views) or its radiance volume. Against the Mitsuba
/// full-GI reference (256², 4 samples per light, default settings) the indirect light must
/// close most of the gap that direct light alone leaves.
#[test]
fn gi_of_area_lights_approaches_the_mitsuba_reference() {
    use voxgi::gi::{GiMethod, GiSettings, RadianceSource};
    let scene = area_light_scene();
    let gi = reference("gi");
    let mut rel_mse = Vec::new();
    for (method, radiance_source) in [
        (GiMethod::None, RadianceSource::Maps),
        (GiMethod::Pathtrace, RadianceSource::Maps),
        (GiMethod::Hemisphere, RadianceSource::Maps),
        (GiMethod::Hemisphere, RadianceSource::Volume),
    ] {
        let mut settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                method,
                radiance_source,
                ..Default::default()
            },
            ..Default::default()
        };
        settings.shadow.area_samples = Some(4);
        let m = compare(&gi, &render(&scene, &settings), None).expect("same size");
        rel_mse.push(m.rel_mse);
    }
    let [direct, path, maps, volume] = rel_mse[..] else {
        unreachable!("four methods")
    };
    println!(
        "vs full GI: direct only {direct:.5}, path tracer {path:.5}, hemisphere with light \
         maps {maps:.5}, with the radiance volume {volume:.5}"
    );
    // Measured (lavapipe): direct only 0.0068 (the missing indirect light plus 4 samples'
    // penumbra steps), path tracer 0.00157 (0.00089 with 16 samples), hemisphere 0.00184 with
    // light maps and 0.00181 with the volume. Bounds: twice each method's value, and a third
    // of the direct-only error.
    assert!(path < 0.0032, "path tracer relMSE {path}");
    assert!(maps < 0.0037, "hemisphere (light maps) relMSE {maps}");
    assert!(
        volume < 0.0037,
        "hemisphere (radiance volume) relMSE {volume}"
    );
    for m in [path, maps, volume] {
        assert!(m < direct / 3.0, "{rel_mse:?}");
    }
}

/// Every sample is a light with a shadow view: too many are refused before any GPU work with
/// an error naming the way out.
#[test]
fn too_many_samples_are_clear_errors() {
    use voxgi::render::{RenderError, Renderer};
    let scene = area_light_scene();
    let ctx = common::context();
    let mut settings = RenderSettings {
        width: 64,
        height: 64,
        ..Default::default()
    };
    // Two area lights of 64 samples: 128 lights.
    settings.shadow.area_samples = Some(64);
    let e = Renderer::new(&ctx, &scene, settings.clone())
        .err()
        .expect("128 lights");
    assert!(matches!(e, RenderError::TooManyLights(128)), "{e}");
    assert!(e.to_string().contains("--area-samples"), "{e}");
    settings.shadow.area_samples = Some(65);
    let e = Renderer::new(&ctx, &scene, settings.clone())
        .err()
        .expect("65 samples");
    assert!(e.to_string().contains("--area-samples"), "{e}");
    common::assert_no_validation_messages(&ctx);
}

/// PCSS (one view per rectangle, two hemispheres per sphere, blocker search, penumbra
/// estimate, Poisson PCF) against sampled sub-lights and the Mitsuba direct reference.
/// Measured (lavapipe, 256²): sampled 16 relMSE 0.00105, PCSS 0.0071 (0.0070 while spheres
/// were still sampled under PCSS; its
/// residue: one view's blockers stand for the whole light, averaged blocker depth, 16-tap
/// noise). Bounds: PCSS at most twice its measured value, and sampled at least 3× more
/// accurate (measured 6.7×), the reason `sampled` is the default. That PCSS's shadows are soft,
/// and how wide, is `pcss_penumbra_has_the_estimated_width`.
#[test]
fn pcss_is_soft_but_less_accurate_than_sampling() {
    use voxgi::light::AreaShadow;
    let scene = area_light_scene();
    let direct = reference("direct");
    let mut rel_mse = Vec::new();
    for technique in [AreaShadow::Sampled, AreaShadow::Pcss] {
        let mut settings = RenderSettings {
            width: 256,
            height: 256,
            ..Default::default()
        };
        settings.shadow.area_technique = technique;
        let m = compare(&direct, &render(&scene, &settings), None).expect("same size");
        println!("{technique:?}: {m:?}");
        rel_mse.push(m.rel_mse);
    }
    assert!(rel_mse[1] < 0.014, "PCSS relMSE {}", rel_mse[1]);
    assert!(rel_mse[0] < rel_mse[1] / 3.0, "sampled vs PCSS {rel_mse:?}");
}

/// PCSS behind the straight edge, a square light s = 0.3 m: the continuous light's 10%–90%
/// penumbra is 0.8 s H_B/(H − H_B) = 0.080 m (linear profile, see the rectangle test). PCSS
/// estimates w = s (z − d_b)/d_b from the blockers' mean distance (here exactly the plate's
/// d_b) and filters a disk of radius w/2, whose profile behind an edge is the circular segment
/// crossing 10% and 90% at ∓0.687 radii: 0.687 w = 0.069 m. Bound: within 25% of that (the
/// disk-vs-square shape, 16 taps, the plate's thickness); one hard shadow would be about a
/// PCF kernel wide (about 0.02 m).
#[test]
fn pcss_penumbra_has_the_estimated_width() {
    use voxgi::light::AreaShadow;
    let s_m = 0.3;
    let scene = penumbra_scene(&format!(
        "kind = \"rectangle\"\nposition = [0, {H}, 1]\nnormal = [0, -1, 0]\n\
         width_axis = [1, 0, 0]\nwidth_m = {s_m}\nheight_m = {s_m}\nradiance_w_sr_m2 = 10"
    ));
    let mut settings = RenderSettings {
        width: 256,
        height: 128,
        ..Default::default()
    };
    settings.shadow.area_technique = AreaShadow::Pcss;
    let img = render(&scene, &settings);
    let (x10, x90) = ten_ninety(&floor_profile(&img, &scene, -0.3, 0.3));
    let expected = 0.687 * s_m * H_B / (H - H_B);
    println!("PCSS 10%-90% penumbra [{x10:.4}, {x90:.4}] m, expected width {expected:.4} m");
    assert!(
        ((x90 - x10) - expected).abs() < 0.25 * expected,
        "PCSS penumbra {} m, expected {expected} m",
        x90 - x10
    );
}

/// PCSS of a whole sphere (`--area-shadows pcss`: a uniform emitter at its centre with two
/// paraboloid hemispheres, s = the diameter 2R). Its filter disk, radius w/2 with
/// w = 2R (z − d_b)/d_b, is the sphere's own apparent disk projected through the edge, so its
/// 10%–90% width is the continuous sphere's: 0.687 w = 1.374 R·H_B/(H − H_B) (the circular
/// segment of `sphere_penumbra_behind_an_edge_matches_similar_triangles`). Tolerance 25%, as
/// for the rectangle: 16 Poisson taps and the blocker search's sampling.
#[test]
fn pcss_of_a_sphere_has_the_sphere_penumbra() {
    use voxgi::light::AreaShadow;
    let r_m = 0.15;
    let scene = penumbra_scene(&format!(
        "kind = \"sphere\"\nposition = [0, {H}, 1]\nradius_m = {r_m}\nradiance_w_sr_m2 = 50"
    ));
    let mut settings = RenderSettings {
        width: 256,
        height: 128,
        ..Default::default()
    };
    settings.shadow.area_technique = AreaShadow::Pcss;
    let img = render(&scene, &settings);
    let (x10, x90) = ten_ninety(&floor_profile(&img, &scene, -0.3, 0.3));
    let expected = 1.374 * r_m * H_B / (H - H_B);
    println!("sphere PCSS 10%-90% penumbra [{x10:.4}, {x90:.4}] m, expected width {expected:.4} m");
    assert!(
        ((x90 - x10) - expected).abs() < 0.25 * expected,
        "sphere PCSS penumbra {} m, expected {expected} m",
        x90 - x10
    );
    // Lit floor beyond the edge: the point light of intensity L·πR² gives the sphere's exact
    // irradiance E = π L (R/d)² cos θ (the sphere wholly above the floor's horizon). The 64
    // sampled elements (facing outward, each L·A_i·cos) are an independent approximation of
    // the same integral; bound 3%.
    settings.shadow.area_technique = AreaShadow::Sampled;
    settings.shadow.area_samples = Some(64);
    let sampled = render(&scene, &settings);
    let mean = |img: &HdrImage| {
        let p = floor_profile(img, &scene, 0.2, 0.3);
        p.iter().map(|&(_, v)| f64::from(v)).sum::<f64>() / p.len() as f64
    };
    let (pcss_lit, sampled_lit) = (mean(&img), mean(&sampled));
    println!("lit floor: PCSS sphere {pcss_lit:.5}, 64 samples {sampled_lit:.5}");
    assert!(
        (pcss_lit / sampled_lit - 1.0).abs() < 0.03,
        "PCSS sphere {pcss_lit} vs sampled {sampled_lit}"
    );
}

//! Area lights rendered as sums of sampled sub-lights (`voxgi::light::area`): the penumbra
//! behind a straight edge against similar triangles, and convergence to the Mitsuba 3
//! direct-light reference of `assets/scenes/area_light.toml` as the sample count grows.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::light::area::grid_for;
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::Scene;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn render(scene: &Scene, settings: &RenderSettings) -> HdrImage {
    let ctx = common::context();
    let out = render_image(&ctx, scene, settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    out.hdr
}

// The penumbra scene: a floor at y = 0, a plate over x < 0, 0 < z < 2 at height H_B (0.02 m
// thick), and a rectangle light at height H above z = 1 facing down, S_M wide along x and thin
// along z, so that the floor's profile across the edge (along x at z = 1) depends on the
// light's width only. The camera is below the plate, so it sees the floor under it.
const H: f32 = 2.0;
const H_B: f32 = 0.5;
const S_M: f32 = 0.4;

fn penumbra_scene() -> Scene {
    let toml = format!(
        "[camera]\nposition = [0, 0.3, -0.5]\ntarget = [0, 0, 1]\nfov_y_deg = 30\n\
         [[lights]]\nkind = \"rectangle\"\nposition = [0, {H}, 1]\nnormal = [0, -1, 0]\n\
         width_axis = [1, 0, 0]\nwidth_m = {S_M}\nheight_m = 0.025\nradiance_w_sr_m2 = 100\n\
         samples = 16\n\
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

#[test]
fn penumbra_width_behind_an_edge_matches_similar_triangles() {
    let scene = penumbra_scene();
    let settings = RenderSettings {
        width: 256,
        height: 128,
        ..Default::default()
    };
    let img = render(&scene, &settings);
    let profile = floor_profile(&img, &scene, -0.3, 0.3);
    let mean = |a: f32, b: f32| {
        let v: Vec<f32> = profile
            .iter()
            .filter(|(x, _)| (a..=b).contains(x))
            .map(|p| p.1)
            .collect();
        v.iter().sum::<f32>() / v.len() as f32
    };
    // Umbra and fully lit plateaus, well outside the penumbra (|x| <= 0.067 m).
    let (lo, hi) = (mean(-0.3, -0.15), mean(0.15, 0.3));
    assert!(lo < 0.02 * hi, "umbra {lo} vs lit {hi}");
    let (x10, x90) = (
        crossing(&profile, lo, hi, 0.1),
        crossing(&profile, lo, hi, 0.9),
    );
    // Similar triangles: the light point at lateral offset a casts the edge (0, H_B) to the
    // floor at x = -a k, k = H_B / (H - H_B) = (d_r - d_b) / d_b with d_r = H, d_b = H - H_B.
    // The whole light (a in [-s/2, s/2]) gives the penumbra w = s k = 0.133 m, across which the
    // visible fraction of a rectangle grows linearly: its 10%-90% part is 0.8 w = 0.107 m,
    // centred on x = 0 (the edge seen from the light's centre).
    let k = H_B / (H - H_B);
    let w = S_M * k;
    // The 16 samples along x (grid_for) make a staircase of 16 steps of w/16: the profile passes
    // 10% at the 2nd step and 90% at the 15th, 13/16 w apart.
    assert_eq!(grid_for(16, S_M / 0.025), (16, 1));
    let expected = 13.0 / 16.0 * w;
    let measured = x90 - x10;
    // Tolerance: one step (w/16 = 8 mm, where the PCF blur moves a crossing to the
    // neighbouring step), two pixels (one at each crossing; 6.4 mm each: 2 tan 15° per 128
    // rows at the 1.53 m from the camera to (0, 0, 1)),
    // the plate's thickness (0.02 m in d_b = 1.5 m: 1.3% of k) and the PCF kernel
    // (3 texels of 2/1024 rad at 1.5 m, times H / d_b: 12 mm).
    let px_m = 2.0 * (0.3f32.hypot(1.5)) * 15f32.to_radians().tan() / 128.0;
    let tol = w / 16.0 + 2.0 * px_m + 0.013 * w + 0.012;
    println!("10%-90% penumbra: measured {measured:.4} m, expected {expected:.4} m +- {tol:.4} (continuous light: {:.4}); centre {:.4} m", 0.8 * w, 0.5 * (x10 + x90));
    assert!(
        (measured - expected).abs() <= tol,
        "penumbra {measured} m, expected {expected} m +- {tol}"
    );
    assert!(
        (0.5 * (x10 + x90)).abs() <= px_m + w / 32.0,
        "penumbra centred at {} m, expected 0",
        0.5 * (x10 + x90)
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
/// hit reads the samples' paraboloid shadow maps. Against the Mitsuba full-GI reference
/// (256², 4 samples per light, default path-tracer settings) the indirect light must close
/// most of the gap that direct light alone leaves.
#[test]
fn path_traced_gi_of_area_lights_approaches_the_mitsuba_reference() {
    use voxgi::gi::{GiMethod, GiSettings};
    let scene = area_light_scene();
    let gi = reference("gi");
    let mut rel_mse = Vec::new();
    for method in [GiMethod::None, GiMethod::Pathtrace] {
        let mut settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                method,
                ..Default::default()
            },
            ..Default::default()
        };
        settings.shadow.area_samples = Some(4);
        let m = compare(&gi, &render(&scene, &settings), None).expect("same size");
        rel_mse.push(m.rel_mse);
    }
    println!(
        "vs full GI: direct only {:.5}, path tracer {:.5}",
        rel_mse[0], rel_mse[1]
    );
    // Measured (lavapipe): direct only 0.0068 (the missing indirect light plus 4 samples'
    // penumbra steps), path tracer 0.00157 (0.00089 with 16 samples). Bounds: twice the
    // path tracer's value, and a third of the direct-only error.
    assert!(rel_mse[1] < 0.0032, "path tracer relMSE {}", rel_mse[1]);
    assert!(rel_mse[1] < rel_mse[0] / 3.0, "{rel_mse:?}");
}

/// Every sample is a light with a shadow view: too many are refused before any GPU work with
/// an error naming the way out, and so are GI methods that would read light maps the samples'
/// paraboloid views do not have.
#[test]
fn too_many_samples_and_light_map_gi_are_clear_errors() {
    use voxgi::gi::{GiMethod, GiSettings};
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
    settings.shadow.area_samples = Some(2);
    for method in [GiMethod::Vpl, GiMethod::Hemisphere] {
        settings.gi = GiSettings {
            method,
            ..Default::default()
        };
        let e = Renderer::new(&ctx, &scene, settings.clone())
            .err()
            .expect("light maps");
        assert!(
            matches!(e, RenderError::AreaLightsNeedNoLightMaps(_)),
            "{e}"
        );
        assert!(e.to_string().contains("--gi pathtrace"), "{e}");
    }
    common::assert_no_validation_messages(&ctx);
}

//! Screen-space GI (`--gi ssgi`, Oetke 2017 §2.3, §5.1–5.3, §7.5): a single plane receives
//! nothing from itself; in a closed sphere lit from its centre one frame's gather matches
//! Eq. 2.12 integrated on the CPU over the visible sphere, and the feedback loop stays below
//! the furnace's closed form and converges; on the Cornell box it beats direct light against
//! the Mitsuba reference. Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::gi::{GiMethod, GiSettings, SsgiResolution, SsgiSettings};
use voxgi::scene::Scene;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn ssgi(frames: u32, ssgi: SsgiSettings) -> GiSettings {
    GiSettings {
        method: GiMethod::Ssgi,
        accumulate_frames: frames,
        ssgi,
        ..Default::default()
    }
}

fn render(scene: &Scene, size: u32, gi: GiSettings) -> HdrImage {
    common::render_with_gi(scene, size, gi).hdr
}

#[test]
fn a_single_plane_receives_no_indirect_light() {
    // Every sender lies in the receiver's plane: cos θ = n·(x_s − x)/‖x_s − x‖ = 0 but for the
    // depth reconstruction's rounding (|n·v| below 1e-5 m at these distances, so cos θ·cos θ'
    // < 1e-8 for senders beyond 0.1 m), so the indirect light is below 1e-6 of the direct.
    let text =
        "[camera]\nposition = [0.3, 1.5, -1.5]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 60.0\n\
        [[lights]]\nkind = \"directional\"\ndirection = [0.3, -1.0, 0.4]\nirradiance_w_m2 = 2.0\n\
        [[objects]]\nbuiltin = \"quad\"\nscale = [4.0, 1.0, 4.0]\n";
    let scene = Scene::from_toml_str(text, Path::new("plane"), Path::new(ROOT)).expect("scene");
    let direct = render(&scene, 64, GiSettings::default());
    let lit = render(&scene, 64, ssgi(3, SsgiSettings::default()));
    let mut max_rel = 0.0f32;
    for (d, l) in direct.data.iter().zip(&lit.data) {
        assert!(l[0] >= d[0] - 1e-6, "indirect light is never negative");
        if d[0] > 0.0 {
            max_rel = max_rel.max((l[0] - d[0]) / d[0]);
        }
    }
    println!("single plane: largest indirect / direct {max_rel:e}");
    assert!(max_rel < 1e-6, "a plane lights itself: {max_rel}");
}

/// A closed sphere of radius 1 m and albedo A seen from its centre with a 90° field of view,
/// a point light at the centre: the direct radiance L_d is uniform.
const FURNACE: &str = r#"
[camera]
position = [0.0, 0.0, 0.0]
target = [0.0, 0.0, 1.0]
fov_y_deg = 90.0
near = 0.01
far = 10.0
[[lights]]
kind = "point"
position = [0.0, 0.0, 0.0]
intensity_w_sr = [1.0, 1.0, 1.0]
[[objects]]
builtin = "sphere"
scale = 2.0
material = { albedo = [0.5, 0.5, 0.5] }
"#;
const ALBEDO: f32 = 0.5;
const FURNACE_SIZE: u32 = 64;
/// Half-width of the central window the furnace renders are read in.
const WINDOW: u32 = 4;

fn furnace_scene() -> Scene {
    Scene::from_toml_str(FURNACE, Path::new("furnace"), Path::new(ROOT)).expect("scene")
}

/// The window's mean red radiance.
fn window_mean(img: &HdrImage) -> f32 {
    let (s, w) = (FURNACE_SIZE, WINDOW);
    let mut sum = 0.0;
    for y in s / 2 - w..s / 2 + w {
        for x in s / 2 - w..s / 2 + w {
            sum += img.data[(y * s + x) as usize][0];
        }
    }
    sum / (4 * w * w) as f32
}

/// Eq. 2.12 integrated over the visible sphere for the receiver seen through NDC point
/// `(u, v)`: I = ∫ cos θ cos θ' / (d² + 0.1) dA. On a sphere of radius R every chord d makes
/// equal angles with both (inward) normals, cos θ = cos θ' = d / 2R; a point seen through
/// image-plane point (x, y, 1) has dA = dx dy cos³α · R² / cos β with cos α = 1/‖(x, y, 1)‖
/// and cos β = 1 (the view ray is radial). Midpoint rule on n² cells of the image plane.
fn sphere_gather(u: f32, v: f32, n: u32) -> f32 {
    let tan = 1.0f32; // tan(90°/2)
    let receiver = Vec3::new(u * tan, v * tan, 1.0).normalize();
    let cell = 2.0 * tan / n as f32;
    let mut sum = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let x = -tan + (i as f32 + 0.5) * cell;
            let y = -tan + (j as f32 + 0.5) * cell;
            let p = Vec3::new(x, y, 1.0);
            let cos_alpha = 1.0 / p.length();
            let d2 = (p.normalize() - receiver).length_squared();
            let kernel = (d2 / 4.0) / (d2 + 0.1);
            sum += f64::from(cell * cell * cos_alpha.powi(3) * kernel);
        }
    }
    sum as f32
}

/// The CPU prediction of (L − L_d) / L_d over the window: A/π · I, averaged over its pixels.
fn predicted_one_bounce() -> f32 {
    let (s, w) = (FURNACE_SIZE, WINDOW);
    let mut sum = 0.0;
    for y in s / 2 - w..s / 2 + w {
        for x in s / 2 - w..s / 2 + w {
            let ndc = |p: u32| (p as f32 + 0.5) / s as f32 * 2.0 - 1.0;
            sum += ALBEDO / std::f32::consts::PI * sphere_gather(ndc(x), ndc(y), 256);
        }
    }
    sum / (4 * w * w) as f32
}

#[test]
fn one_frame_in_the_sphere_matches_eq_2_12_integrated_on_the_cpu() {
    let scene = furnace_scene();
    let direct = window_mean(&render(&scene, FURNACE_SIZE, GiSettings::default()));
    let predicted = predicted_one_bounce();
    for resolution in [
        SsgiResolution::Full,
        SsgiResolution::Half,
        SsgiResolution::Quarter,
    ] {
        let divisor = resolution.divisor();
        let settings = SsgiSettings {
            resolution,
            ..Default::default()
        };
        let lit = window_mean(&render(&scene, FURNACE_SIZE, ssgi(1, settings)));
        let measured = lit / direct - 1.0;
        println!("sphere, GI at 1/{divisor}: indirect/direct {measured:.5}, Eq. 2.12 on the CPU {predicted:.5}");
        let tolerance = if divisor >= 4 {
            TOLERANCE_QUARTER
        } else {
            TOLERANCE
        };
        assert!(
            (measured - predicted).abs() < tolerance * predicted,
            "1/{divisor}: {measured} vs {predicted}"
        );
    }
}

/// Relative tolerance of the one-frame gather at GI resolution 1/1 and 1/2. Measured (64², 64
/// samples): 0.53% and 0.59% off (`cargo test --test ssgi sphere -- --nocapture`); the residue
/// is the spiral's sampling noise averaged over the window, the tessellated sphere and the
/// 0.5-texel disk left out. 2% leaves more than three times that.
const TOLERANCE: f32 = 0.02;
/// The same at 1/4: measured 7.3% (a 16² GI level, where the sphere's curvature within a texel
/// and the upsampling show); 10% leaves a third more.
const TOLERANCE_QUARTER: f32 = 0.1;

#[test]
fn feedback_in_the_sphere_stays_below_the_furnace_value_and_converges() {
    // Each frame feeds the last frame's indirect light back: L_t = L_d + A/π · E_t with
    // E_t = Σ (L_d + A/π E_{t−1}) · w over the senders; since Σ w ≤ ∫ cos θ cos θ' / d² dA ≤ π
    // (the +0.1 m² only lowers it), L_t ≤ L_d (1 + A + A² + …) = L_d / (1 − A): the furnace
    // value, which full GI reaches in a closed sphere. Screen space sees only the frustum, so
    // the loop converges far below it, to L_d / (1 − A·I/π) for a receiver gathering I.
    let scene = furnace_scene();
    let direct = window_mean(&render(&scene, FURNACE_SIZE, GiSettings::default()));
    let ratio = |frames| {
        window_mean(&render(
            &scene,
            FURNACE_SIZE,
            ssgi(frames, SsgiSettings::default()),
        )) / direct
    };
    let (r1, r20, r30) = (ratio(1), ratio(20), ratio(30));
    let furnace = 1.0 / (1.0 - ALBEDO);
    let one = predicted_one_bounce();
    let converged = 1.0 / (1.0 - one);
    println!("sphere feedback: L/L_d after 1, 20, 30 frames {r1:.5} {r20:.5} {r30:.5}; one bounce predicted {:.5}, geometric series {converged:.5}, furnace {furnace}", 1.0 + one);
    assert!(r30 < furnace, "above the furnace value: {r30}");
    assert!(r30 > r1, "feedback adds bounces: {r30} vs {r1}");
    assert!(
        (r30 - r20).abs() < 0.002 * r30,
        "not converged: {r20} → {r30}"
    );
    // Where it converges: the indirect part r − 1 against the geometric series' converged − 1.
    // Measured 0.06244 against 0.06163, 1.3% off: the one-frame gather's 0.5% (above) plus
    // feeding back a window that is not uniform (receivers near its edge gather less). 3%
    // leaves more than twice that.
    assert!(
        ((r30 - 1.0) - (converged - 1.0)).abs() < 0.03 * (converged - 1.0),
        "converged to {r30}, the geometric series gives {converged}"
    );
}

/// relMSE against the Mitsuba full-GI reference of the Cornell box (256²).
#[test]
fn cornell_beats_direct_light_against_mitsuba() {
    let scene = voxgi::scene::load_scene_arg(Some("cornell")).expect("scene");
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/cornell_gi.exr")).expect("exr");
    let none = compare(
        &reference,
        &render(&scene, 256, GiSettings::default()),
        None,
    )
    .expect("size");
    let lit = compare(
        &reference,
        &render(&scene, 256, ssgi(4, SsgiSettings::default())),
        None,
    )
    .expect("size");
    println!(
        "cornell vs Mitsuba GI: direct relMSE {:.4} FLIP {:.4}; ssgi relMSE {:.4} FLIP {:.4}",
        none.rel_mse, none.flip_mean, lit.rel_mse, lit.flip_mean
    );
    assert!(lit.rel_mse < none.rel_mse && lit.flip_mean < none.flip_mean);
    assert!(lit.rel_mse < MAX_CORNELL_REL_MSE, "{}", lit.rel_mse);
}

/// Measured 0.267 (FLIP 0.572; direct only 0.384, 0.698) at 4 frames, 256², defaults (0.256
/// without the temporal blend, whose τ = 0.9 slows the feedback's bounces); bound with a 5%
/// margin.
const MAX_CORNELL_REL_MSE: f64 = 0.28;

/// The split-sum table against the same integral by a deterministic quadrature on the CPU with
/// the Rust GGX twin: ∫ f_spec(F0) (n·l) dl over the hemisphere on a 1024 × 512 midpoint grid in
/// (cos θ, φ ∈ [0, π], doubled: v lies in the xz plane), which is F0·A + B, so F0 = 0 gives B
/// and F0 = 1 gives A + B. Bound: the table's 1024 Hammersley samples of an integrand in
/// about [0, 1] err by at most a Monte Carlo standard error 1/(2√1024) ≈ 0.016 (QMC does
/// better; measured below 0.002); the quadrature's own error is far smaller at r ≥ 0.3.
#[test]
fn split_sum_table_matches_a_cpu_integration() {
    use voxgi::gi::ssgi_brdf_lut::{BrdfLut, LUT_SIZE};
    let ctx = common::context();
    let lut = BrdfLut::new(&ctx).expect("lut");
    let table = lut.read(&ctx).expect("reads");
    common::assert_no_validation_messages(&ctx);
    let n = Vec3::Z;
    for (i, j) in [(64u32, 64u32), (115, 102), (80, 38), (20, 127)] {
        let n_dot_v = (i as f32 + 0.5) / LUT_SIZE as f32;
        let roughness = (j as f32 + 0.5) / LUT_SIZE as f32;
        let v = Vec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
        let integral = |f0: f32| {
            let (nu, nphi) = (1024, 512);
            let mut sum = 0.0f64;
            for a in 0..nu {
                let c = (a as f32 + 0.5) / nu as f32;
                let s = (1.0 - c * c).sqrt();
                for b in 0..nphi {
                    let phi = (b as f32 + 0.5) / nphi as f32 * std::f32::consts::PI;
                    let l = Vec3::new(s * phi.cos(), s * phi.sin(), c);
                    let f = voxgi::scene::ggx_specular(Vec3::splat(f0), roughness, n, l, v).x;
                    sum += f64::from(f * c);
                }
            }
            (sum * 2.0 * std::f64::consts::PI / (nu * nphi) as f64) as f32
        };
        let b = integral(0.0);
        let a = integral(1.0) - b;
        let [ga, gb] = table[(j * LUT_SIZE + i) as usize];
        println!(
            "LUT n·v {n_dot_v:.3} r {roughness:.3}: GPU A {ga:.4} B {gb:.4}, CPU A {a:.4} B {b:.4}"
        );
        assert!(
            (ga - a).abs() < 0.016 && (gb - b).abs() < 0.016,
            "({i}, {j})"
        );
    }
}

/// `voxgi bench ssgi` end to end on a tiny grid (2 mip filters × 2 resolutions × 1 sample
/// count at 32²): every configuration gets a row with its stages, times and errors. Speed is
/// not asserted; what must hold whatever the device: every stage's per-frame sum is part of
/// the ssgi sum, which is part of the frame's, so their medians are ordered the same way
/// (order statistics are monotone), and the images are scored against the reference.
#[test]
fn bench_ssgi_runs_end_to_end_on_a_tiny_grid() {
    use voxgi::bench::{bench_ssgi, load_reference, SsgiBenchDesc};
    use voxgi::gi::SsgiMips;
    let scene = voxgi::scene::load_scene_arg(Some("cornell")).expect("scene");
    let reference =
        load_reference(&Path::new(ROOT).join("assets/references"), "cornell", 32).expect("exr");
    let desc = SsgiBenchDesc {
        mips: vec![SsgiMips::Fast, SsgiMips::Voting],
        resolutions: vec![SsgiResolution::Full, SsgiResolution::Quarter],
        samples: vec![8],
        size: 32,
        frames: 3,
        warmup: 1,
        gi_frames: 2,
    };
    let ctx = common::context();
    let report = bench_ssgi(&ctx, &scene, "cornell", &reference, &desc).expect("runs");
    common::assert_no_validation_messages(&ctx);
    println!("{}", report.table());
    assert_eq!(report.rows.len(), 4);
    for r in &report.rows {
        let stages: Vec<&str> = r.stages.iter().map(|s| s.stage.as_str()).collect();
        assert_eq!(
            stages,
            ["ssgi_input", "ssgi_mip", "ssgi_gather", "ssgi_upsample"],
            "row {}",
            r.number
        );
        for s in &r.stages {
            let t = s.time;
            assert!(t.min_ms <= t.median_ms && t.median_ms <= t.max_ms, "{s:?}");
            assert!(
                t.median_ms <= r.ssgi.median_ms,
                "{s:?} vs ssgi {:?}",
                r.ssgi
            );
        }
        assert!(r.ssgi.median_ms <= r.frame.median_ms, "{r:?}");
        assert!(
            r.rel_mse.is_finite() && r.rel_mse > 0.0 && r.flip > 0.0,
            "{r:?}"
        );
    }
    assert_eq!(
        (report.rows[0].mips.as_str(), report.rows[3].mips.as_str()),
        ("fast", "voting")
    );
    assert_eq!(report.csv().lines().count(), 5);
    // Indirect light brings the full-resolution image closer to the reference than direct
    // light alone (the Cornell test above, at this size).
    assert!(report.rows[0].rel_mse < report.direct_rel_mse, "{report:?}");
}

/// The reprojection scene: a grey back wall facing the camera at z = 2 (x ∈ [−1, 1.5],
/// y ∈ [−1.5, 1.5]), a red left wall at x = −1 (z ∈ [0, 2]) that bounces light onto it (so
/// its indirect light varies across the image), a grey cube at z ∈ [0, 0.4] in front of it
/// (1–1.4 m from the camera: its image moves 3 − 1 = 2 pixels more than the wall's per
/// wall-pixel step of the camera, uncovering wall), and a point light; the camera looks along
/// +z from z = −1 (the back wall 3 m away).
const REPROJECT_SCENE: &str = r#"
[camera]
position = [0.0, 0.0, -1.0]
forward = [0.0, 0.0, 1.0]
fov_y_deg = 60.0
[[lights]]
kind = "point"
position = [0.0, 0.5, 0.5]
intensity_w_sr = [2.0, 2.0, 2.0]
[[objects]]
builtin = "quad"
scale = [2.5, 1.0, 3.0]
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.25, 0.0, 2.0]
material = { albedo = [0.7, 0.7, 0.7] }
[[objects]]
builtin = "quad"
scale = [3.0, 1.0, 2.0]
rotate_deg = [0.0, 0.0, -90.0]
translate = [-1.0, 0.0, 1.0]
material = { albedo = [0.9, 0.1, 0.1] }
[[objects]]
builtin = "cube"
scale = 0.4
translate = [0.3, -0.3, 0.2]
material = { albedo = [0.5, 0.5, 0.5] }
"#;

const REPROJECT_SIZE: u32 = 64;

/// Where the ray through pixel `px` of `cam` first meets the scene: `Some(true)` on the back
/// wall, `Some(false)` on the cube or the left wall, `None` on nothing (the cube by a slab
/// test, the walls as planes within their bounds).
fn back_wall_seen(cam: &voxgi::scene::Camera, px: [u32; 2]) -> Option<(bool, Vec3)> {
    let n = REPROJECT_SIZE;
    let (near, far) = cam.pixel_ray_points(px[0], px[1], n, n);
    let d = far - near;
    let mut best: Option<(f32, bool, Vec3)> = None;
    let mut consider = |t: f32, back: bool| {
        if t > 0.0 && best.is_none_or(|b| t < b.0) {
            best = Some((t, back, near + d * t));
        }
    };
    let t = (2.0 - near.z) / d.z;
    let p = near + d * t;
    if (-1.0..=1.5).contains(&p.x) && p.y.abs() <= 1.5 {
        consider(t, true);
    }
    let t = (-1.0 - near.x) / d.x;
    let p = near + d * t;
    if (0.0..=2.0).contains(&p.z) && p.y.abs() <= 1.5 {
        consider(t, false);
    }
    let (lo, hi) = (Vec3::new(0.1, -0.5, 0.0), Vec3::new(0.5, -0.1, 0.4));
    let (t0, t1) = ((lo - near) / d, (hi - near) / d);
    let (tmin, tmax) = (t0.min(t1).max_element(), t0.max(t1).min_element());
    if tmin <= tmax {
        consider(tmin, false);
    }
    best.map(|(_, back, p)| (back, p))
}

/// The ssgi history's reprojection under a moving camera (Oetke 2017 §5.1), tested where its
/// nearest-texel lookup must be exact: the camera steps sideways by exactly one pixel's
/// footprint on the back wall (3 m · 2 tan 30° / 64), so every back-wall point seen at pixel
/// p after the step was at the centre of a pixel q (q = p ± 1) before it. Frame k renders 3
/// frames at C_k; frame k + 1 renders once at C_{k+1} with the same renderer. Without feedback
/// its gather equals a fresh render's first frame at C_{k+1} (same inputs, same seed after the
/// restart), and its irradiance is mix(E_fresh, E_k(q), τ·w) with w = 1 where the depths agree:
/// in indirect radiance (the image minus the direct-only image of the same camera; ρ is that
/// of the same wall point), I_{k+1}(p) = (1 − τ)·I_fresh(p) + τ·I_k(q), exactly up to f32
/// rounding: the mix, the composite's d + ρ/π·E and the subtraction of d (|d| ≤ 1, a few ulps
/// of 6e-8 each) stay within 1e-5. Back-wall pixels that the cube hid at C_k (q sees the cube,
/// 1–1.4 m away: its clip w differs from the wall's by over 50%, far beyond the 5% where the
/// shader's depth test gives w = 0) must take the fresh value alone. Reading the history
/// unreprojected (q = p) is off by far more: the red wall's bounce varies across the image.
#[test]
fn moving_camera_reprojects_the_ssgi_history_exactly_by_a_whole_texel() {
    let scene = Scene::from_toml_str(REPROJECT_SCENE, Path::new("reproject"), Path::new(ROOT))
        .expect("scene");
    let n = REPROJECT_SIZE;
    let footprint = 3.0 * 2.0 * 30f32.to_radians().tan() / n as f32;
    let mut moved = scene.clone();
    moved.camera.position.x += footprint;
    let tau = SsgiSettings::default().history_weight;
    let gi = |method| GiSettings {
        method,
        filter_radius: 0,
        ssgi: SsgiSettings {
            feedback: false,
            resolution: SsgiResolution::Full,
            ..Default::default()
        },
        ..Default::default()
    };
    let settings = |method| voxgi::render::RenderSettings {
        width: n,
        height: n,
        gi: gi(method),
        ..Default::default()
    };
    let ctx = common::context();
    let seq = voxgi::render::render_sequence(
        &ctx,
        &scene,
        &settings(GiMethod::Ssgi),
        3,
        std::slice::from_ref(&moved),
    )
    .expect("renders");
    let render = |s: &Scene, method| {
        voxgi::render::render_image(&ctx, s, &settings(method))
            .expect("renders")
            .hdr
    };
    let fresh = render(&moved, GiMethod::Ssgi);
    let direct_k = render(&scene, GiMethod::None);
    let direct_k1 = render(&moved, GiMethod::None);
    common::assert_no_validation_messages(&ctx);
    let indirect = |img: &HdrImage, direct: &HdrImage, i: usize| {
        let (a, d) = (img.data[i], direct.data[i]);
        [a[0] - d[0], a[1] - d[1], a[2] - d[2]]
    };
    let vp_k = scene.camera.view_proj(1.0);
    let (mut exact, mut disoccluded) = (0, 0);
    let (mut worst, mut worst_unprojected, mut worst_disoccluded) = (0.0f32, 0.0f32, 0.0f32);
    let mut largest = 0.0f32;
    for y in 0..n {
        for x in 0..n {
            let Some((true, p)) = back_wall_seen(&moved.camera, [x, y]) else {
                continue;
            };
            // Where the wall point was at C_k: a pixel centre, by construction.
            let ndc = vp_k.project_point3(p);
            let qf = [
                (ndc.x * 0.5 + 0.5) * n as f32 - 0.5,
                (ndc.y * 0.5 + 0.5) * n as f32 - 0.5,
            ];
            let q = [qf[0].round(), qf[1].round()];
            assert!(
                (qf[0] - q[0]).abs() < 1e-3 && (qf[1] - q[1]).abs() < 1e-3,
                "pixel ({x}, {y}) was not at a pixel centre: {qf:?}"
            );
            if q.iter().any(|&v| v < 0.0 || v >= n as f32) {
                continue;
            }
            let (qx, qy) = (q[0] as u32, q[1] as u32);
            assert_eq!(qy, y, "a sideways step moves pixels sideways");
            let i = (y * n + x) as usize;
            let j = (qy * n + qx) as usize;
            let next = indirect(&seq.frames[0], &direct_k1, i);
            let new = indirect(&fresh, &direct_k1, i);
            let before = indirect(&seq.warm, &direct_k, j);
            let unmoved = indirect(&seq.warm, &direct_k, i);
            let visible_before = matches!(back_wall_seen(&scene.camera, [qx, qy]), Some((true, _)));
            for c in 0..3 {
                largest = largest.max(before[c].abs());
                if visible_before {
                    let want = (1.0 - tau) * new[c] + tau * before[c];
                    worst = worst.max((next[c] - want).abs());
                    let naive = (1.0 - tau) * new[c] + tau * unmoved[c];
                    worst_unprojected = worst_unprojected.max((next[c] - naive).abs());
                } else {
                    worst_disoccluded = worst_disoccluded.max((next[c] - new[c]).abs());
                }
            }
            if visible_before {
                exact += 1;
            } else {
                disoccluded += 1;
            }
        }
    }
    println!(
        "ssgi reprojection by one texel: {exact} pixels, worst {worst:e} (unreprojected \
         {worst_unprojected:e}); {disoccluded} disoccluded, worst {worst_disoccluded:e}; largest \
         indirect radiance {largest}"
    );
    assert!(
        exact > (n * n / 3) as usize,
        "{exact} back-wall pixels compared"
    );
    assert!(worst < 1e-5, "reprojected history off by {worst}");
    assert!(disoccluded > 0, "the step uncovers wall the cube hid");
    assert!(
        worst_disoccluded < 1e-5,
        "a disoccluded pixel kept history: {worst_disoccluded}"
    );
    assert!(
        worst_unprojected > 100.0 * 1e-5,
        "the history varies across the image: {worst_unprojected}"
    );
}

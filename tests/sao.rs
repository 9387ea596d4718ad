//! Modified SAO (Oetke 2017 §2.5): a flat floor has no obscurance (exactly 1, and the lit
//! image equals the one without SAO), a 90° corner matches the same estimator, depth pyramid
//! and blur evaluated on the CPU against the analytic geometry, and the joint bilateral
//! upsampling keeps a far surface's AO off a near one across a silhouette. Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::gi::{GiMethod, GiSettings, SaoSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{Camera, Scene};

const SIZE: u32 = 64;

/// A 4 m floor quad (y = 0); with `wall`, a 4 m × 2 m × 1 m box on it whose front face is the
/// plane z = 0 (0 ≤ y ≤ 2, |x| ≤ 2), so floor and face meet in a 90° corner along the x axis.
fn scene(camera: &str, wall: bool) -> Scene {
    let wall = if wall {
        "[[objects]]\nbuiltin = \"cube\"\nscale = [4.0, 2.0, 1.0]\ntranslate = [0.0, 1.0, 0.5]\n"
    } else {
        ""
    };
    let text = format!(
        "{camera}\n[[lights]]\nkind = \"directional\"\ndirection = [0.3, -1.0, 0.4]\n\
         irradiance_w_m2 = 2.0\n\n[[objects]]\nbuiltin = \"quad\"\nscale = [4.0, 1.0, 4.0]\n{wall}"
    );
    Scene::from_toml_str(&text, Path::new("sao test scene"), Path::new(".")).expect("scene")
}

fn settings(sao: Option<SaoSettings>) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        gi: GiSettings {
            method: GiMethod::Hemisphere,
            rays: 1,
            sao,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Renders `scene` and returns the red channel of the radiance (the AO term in the view).
fn render(scene: &Scene, sao: Option<SaoSettings>) -> Vec<f32> {
    let ctx = common::context();
    let out = render_image(&ctx, scene, &settings(sao)).expect("renders");
    common::assert_no_validation_messages(&ctx);
    out.hdr.data.iter().map(|p| p[0]).collect()
}

fn view(radius_m: f32) -> Option<SaoSettings> {
    Some(SaoSettings {
        radius_m,
        view: true,
        ..Default::default()
    })
}

#[test]
fn sao_of_a_flat_floor_is_exactly_one_and_leaves_the_image_unchanged() {
    // Seen from above: every tap lies in the centre's tangent plane, v·n = 0 up to the depth
    // reconstruction's rounding (|v·n| < 1e-5 m here), far below β = 0.04 m, so every term of
    // the sum is max(negative, 0) = 0 and A = 1^k = 1; the blur averages ones with
    // normalized weights (Σwᵢ·1 / Σwᵢ = 1 exactly). So: exactly 1, no epsilon.
    let s = scene(
        "[camera]\nposition = [0.1, 2.0, 0.2]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\nfov_y_deg = 50.0\n",
        false,
    );
    let ao = render(&s, view(1.8));
    let (i, min) = ao
        .iter()
        .enumerate()
        .fold((0, 1.0f32), |m, (i, &a)| if a < m.1 { (i, a) } else { m });
    assert!(
        ao.iter().all(|&a| a == 1.0),
        "AO of a flat floor: {min} at pixel {i} (x {}, y {})",
        i as u32 % SIZE,
        i as u32 / SIZE
    );
    // And A = 1 multiplies the indirect light by exactly 1.
    let lit_sao = render(&s, Some(SaoSettings::default()));
    let lit = render(&s, None);
    assert_eq!(lit_sao, lit, "SAO of 1 changes nothing");
}

/// The visible surface through the centre of pixel `px` and its normal: the nearest hit of
/// the camera ray with the floor (y = 0, |x|, |z| ≤ 2) and the box face (z = 0, 0 ≤ y ≤ 2,
/// |x| ≤ 2).
fn surface(cam: &Camera, px: [i32; 2]) -> Option<(Vec3, Vec3)> {
    let (near, far) = cam.pixel_ray_points(px[0] as u32, px[1] as u32, SIZE, SIZE);
    let d = far - near;
    let mut best: Option<(f32, Vec3, Vec3)> = None;
    let mut try_plane = |t: f32, n: Vec3, inside: &dyn Fn(Vec3) -> bool| {
        let p = near + d * t;
        if t > 0.0 && t < 1.0 && inside(p) && best.is_none_or(|b| t < b.0) {
            best = Some((t, p, n));
        }
    };
    try_plane(-near.y / d.y, Vec3::Y, &|p| {
        p.x.abs() <= 2.0 && p.z.abs() <= 2.0
    });
    try_plane(-near.z / d.z, Vec3::NEG_Z, &|p| {
        p.x.abs() <= 2.0 && (0.0..=2.0).contains(&p.y)
    });
    best.map(|(_, p, n)| (p, n))
}

/// The sizes of level `k` of the depth pyramid (Vulkan mips: halved, rounded down, ≥ 1).
fn level_size(k: u32) -> [i32; 2] {
    [(SIZE >> k).max(1) as i32; 2]
}

/// Levels of the depth pyramid at `SIZE`² (`sao::depth_levels`: six from 32² up).
const LEVELS: u32 = 6;

/// The full-resolution pixel whose depth and normal texel `q` of level `k` holds:
/// `glsl/sao_depth.comp`'s rotated-grid subsample, child 2q + ((q.y & 1) ^ 1, (q.x & 1) ^ 1)
/// clamped to the finer level, followed down to level 0.
fn source_pixel(mut q: [i32; 2], k: u32) -> [i32; 2] {
    for j in (1..=k).rev() {
        let s = level_size(j - 1);
        q = [
            (2 * q[0] + ((q[1] & 1) ^ 1)).min(s[0] - 1),
            (2 * q[1] + ((q[0] & 1) ^ 1)).min(s[1] - 1),
        ];
    }
    q
}

/// The per-pixel rotation φ of `glsl/sao.comp` (the same integer hash).
fn rotation(c: [i32; 2], seed: u32) -> f32 {
    let mut h = (c[0] as u32)
        .wrapping_mul(1973)
        .wrapping_add((c[1] as u32).wrapping_mul(9277))
        .wrapping_add(seed.wrapping_mul(26699));
    h = (h ^ (h >> 16)).wrapping_mul(0x7feb352d);
    h = (h ^ (h >> 15)).wrapping_mul(0x846ca68b);
    h ^= h >> 16;
    (h >> 8) as f32 * (std::f32::consts::TAU / 16_777_216.0)
}

fn smoothstep(l: f32, r: f32, x: f32) -> f32 {
    let t = ((x - l) / (r - l)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Oetke 2017 Eq. 2.20–2.22 at the full-resolution pixel `c`, as `glsl/sao.comp` evaluates it:
/// a tap at offset d pixels reads level m = clamp(⌊log2 d⌋ − 4, 0, 5) of the depth pyramid,
/// i.e. the view depth and normal of [`source_pixel`], placed on the tap pixel's own ray.
fn sao_cpu(cam: &Camera, s: &SaoSettings, c: [i32; 2]) -> f32 {
    let Some((p, n)) = surface(cam, c) else {
        return 1.0;
    };
    let z_m = (p - cam.position).dot(cam.forward);
    let px_per_m = SIZE as f32 / (2.0 * (cam.fov_y_deg.to_radians() * 0.5).tan());
    let radius_px = s.radius_m * px_per_m / z_m;
    let phi = rotation(c, 0);
    let taps = s.taps;
    let r2 = s.radius_m * s.radius_m;
    let mut sum = 0.0;
    for i in 0..taps {
        let alpha = (i as f32 + 0.5) / taps as f32;
        let theta = std::f32::consts::TAU * alpha * SaoSettings::SPIRAL_TURNS + phi;
        let off = radius_px * alpha;
        let q = [
            (c[0] as f32 + 0.5 + off * theta.cos()).floor() as i32,
            (c[1] as f32 + 0.5 + off * theta.sin()).floor() as i32,
        ];
        if q.iter().any(|&v| v < 0 || v >= SIZE as i32) {
            continue;
        }
        let msb = (off as i32).checked_ilog2().map_or(-1, |l| l as i32);
        let m = (msb - 4).clamp(0, LEVELS as i32 - 1) as u32;
        let size_m = level_size(m);
        let qm = [
            (q[0] >> m).min(size_m[0] - 1),
            (q[1] >> m).min(size_m[1] - 1),
        ];
        let Some((source, ns)) = surface(cam, source_pixel(qm, m)) else {
            continue;
        };
        let z = (source - cam.position).dot(cam.forward);
        let (near, far) = cam.pixel_ray_points(q[0] as u32, q[1] as u32, SIZE, SIZE);
        let d = far - near;
        let ps = cam.position + d * (z / d.dot(cam.forward));
        let v = ps - p;
        let vv = v.dot(v);
        let f = (r2 - vv).max(0.0);
        let cn = n.dot(ns).abs();
        let sigma = smoothstep(0.01, 0.2, cn) * 0.6 + 0.4 + smoothstep(0.8, 1.0, cn) * 2.0;
        sum += f * f * f * ((v.dot(n) - s.bias) / (vv + s.epsilon_m2)).max(0.0) * sigma;
    }
    let a = (1.0 - 5.0 / (r2 * r2 * r2 * taps as f32) * sum).max(0.0);
    a.powf(s.contrast)
}

/// `glsl/sao_blur.comp` along `dir` over the half-resolution image `ao`.
fn blur_cpu(cam: &Camera, ao: &[f32], dir: [i32; 2]) -> Vec<f32> {
    const W: [f32; 4] = [0.2707, 0.2167, 0.1113, 0.0366];
    let half = SIZE.div_ceil(2) as i32;
    let dist = |q: [i32; 2]| {
        let f = [
            (q[0] * 2).min(SIZE as i32 - 1),
            (q[1] * 2).min(SIZE as i32 - 1),
        ];
        surface(cam, f).map(|(p, _)| p.distance(cam.position))
    };
    let mut out = ao.to_vec();
    for y in 0..half {
        for x in 0..half {
            let Some(z0) = dist([x, y]) else { continue };
            let sigma = 0.02 * z0;
            let (mut sum, mut wsum) = (0.0, 0.0);
            for k in -3i32..=3 {
                let q = [x + dir[0] * k, y + dir[1] * k];
                if q.iter().any(|&v| v < 0 || v >= half) {
                    continue;
                }
                let Some(z) = dist(q) else { continue };
                let w = W[k.unsigned_abs() as usize]
                    * (-(z - z0).powi(2) / (2.0 * sigma * sigma)).exp();
                sum += w * ao[(q[1] * half + q[0]) as usize];
                wsum += w;
            }
            out[(y * half + x) as usize] = sum / wsum;
        }
    }
    out
}

#[test]
fn sao_of_a_corner_matches_the_estimator_on_the_analytic_geometry() {
    // Looking into the corner of floor and box face from 1.5 m, r = 0.6 m: near the crease
    // the face occludes the floor (v·n > β) and vice versa, with σ = 0.4 for the
    // perpendicular pairs; far from it A → 1. The CPU twin evaluates the same estimator and
    // blur with positions from exact ray–plane intersections instead of the depth buffer.
    let s = scene(
        "[camera]\nposition = [0.05, 1.0, -1.5]\ntarget = [0.0, 0.2, 0.0]\nfov_y_deg = 50.0\n",
        true,
    );
    // Fewer taps than the default: the GPU's spiral follows `gi.sao_taps` as the CPU's does.
    let sao = SaoSettings {
        radius_m: 0.6,
        taps: 12,
        view: true,
        ..Default::default()
    };
    let gpu = render(&s, Some(sao));
    let cam = s.camera;
    let half = SIZE.div_ceil(2) as i32;
    let raw: Vec<f32> = (0..half * half)
        .map(|i| sao_cpu(&cam, &sao, [(i % half) * 2, (i / half) * 2]))
        .collect();
    let cpu = blur_cpu(&cam, &blur_cpu(&cam, &raw, [1, 0]), [0, 1]);
    // Pixel (2x, 2y) coincides with half-resolution texel (x, y): the upsampling gives it
    // that texel's value alone (bilinear weight 1, its own depth).
    let mut errs: Vec<f32> = (0..half * half)
        .map(|i| {
            let (x, y) = (i % half, i / half);
            (gpu[(2 * y * SIZE as i32 + 2 * x) as usize] - cpu[i as usize]).abs()
        })
        .collect();
    let min_ao = cpu.iter().cloned().fold(1.0, f32::min);
    errs.sort_by(f32::total_cmp);
    let max_err = errs[errs.len() - 1];
    // The GPU reads positions from a D32F depth buffer: one ulp of depth near 1 (2⁻²⁴) is
    // z²/near · 2⁻²⁴ ≈ 1.5²/0.01 · 6e-8 ≈ 1.3e-5 m at z = 1.5 m; the rasterized normals are
    // exact for these axis-aligned faces. With (r² − v·v)³/r⁶ ≤ 1, σ ≤ 3 and
    // |d/dv (v·n − β)/(v·v + ε)| ≤ 3/(v·v + ε), tap i (at |v| ≈ αᵢ r, r = 0.6 m) moves the
    // sum 5/(r⁶N)·Σ by at most 5/16 · 3 · 3/(αᵢ² r² + ε) per meter of position error (the
    // pyramid's coarser levels put a tap at another pixel's depth, the same on both sides); over
    // the 16 taps that is 2.8 · Σᵢ 1/(αᵢ² r² + ε) ≈ 2.8 · 370 ≈ 1040 per meter, so A = (1 − …)^k
    // (k = 2, the base ≤ 1) moves by at most 2 · 1040 · 1.3e-5 ≈ 0.03 if all errors had one
    // sign; the blur averages, never amplifies. Bound: 0.03 (measured: 1.1e-4). A tap rounded
    // to another pixel (a sin/cos ulp at a pixel edge), a crease pixel classified differently
    // or a difference in the formulas moves A near the crease (A ≈ 0.2–0.9) by more.
    assert!(
        max_err < 0.03,
        "largest |GPU − CPU| {max_err} (mean {})",
        errs.iter().sum::<f32>() / errs.len() as f32
    );
    // The corner is actually obscured (the test is not comparing ones with ones).
    assert!(min_ao < 0.5, "the corner is obscured: min A = {min_ao}");
}

/// The edge scene: the floor and box face of [`scene`] (floor cut to z ≥ −1.4) seen
/// head-on from z = −3, and a 6 m square facing the camera at z = −1.5, turned 20° about the
/// view axis, whose slanted right edge crosses the floor–face crease behind it in the middle
/// of the image (at the crease's row the square's plane is at y = 0.25 m, where its edge is
/// at x = 0).
const EDGE_SCENE: &str = "[camera]\nposition = [0.0, 0.5, -3.0]\nforward = [0.0, 0.0, 1.0]\n\
    fov_y_deg = 50.0\n\
    [[lights]]\nkind = \"directional\"\ndirection = [0.3, -1.0, 0.4]\nirradiance_w_m2 = 2.0\n\
    [[objects]]\nbuiltin = \"quad\"\nscale = [4.0, 1.0, 3.4]\ntranslate = [0.0, 0.0, 0.3]\n\
    [[objects]]\nbuiltin = \"cube\"\nscale = [4.0, 2.0, 1.0]\ntranslate = [0.0, 1.0, 0.5]\n\
    [[objects]]\nbuiltin = \"quad\"\nscale = [6.0, 1.0, 6.0]\nrotate_deg = [-90.0, 0.0, 20.0]\n\
    translate = [-3.54, 1.2, -1.5]\n";

/// Whether the camera ray through pixel `px` meets the front square (z = −1.5) first: it is
/// the nearest surface wherever it is hit (everything else lies at z ≥ −1.4).
fn on_front_square(cam: &Camera, px: [i32; 2]) -> bool {
    let (near, far) = cam.pixel_ray_points(px[0] as u32, px[1] as u32, SIZE, SIZE);
    let d = far - near;
    let p = near + d * ((-1.5 - near.z) / d.z);
    // The square's frame: centre (−3.54, 1.2), axes turned 20° about z, half side 3 m.
    let (s, c) = 20f32.to_radians().sin_cos();
    let (dx, dy) = (p.x + 3.54, p.y - 1.2);
    let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
    u.abs() <= 3.0 && v.abs() <= 3.0
}

#[test]
fn upsampled_sao_does_not_bleed_across_a_depth_edge() {
    // The square has nothing in front of it within r = 1 m (the floor starts 0.1 m behind
    // its plane, the box face 1.5 m), so every tap either lies in its plane (v·n ≈ 0 < β) or
    // behind it (v·n < 0): its AO is exactly 1 at every half-resolution texel, and the blur,
    // whose depth weights across the 1.3 m step are exp(−1.3²/(2·(0.02·1.5)²)) = 0 in f32,
    // keeps it 1. Behind the edge the crease is obscured (A well below 1).
    //
    // Joint bilateral upsampling weighs each of a pixel's (up to) four texels by
    // exp(−Δz²/(2σ²)), σ = 2% of its depth: across the step that weight is 0 in f32, so a
    // pixel's value is a convex combination of its own surface's texels. Bounds, exact up to
    // the f32 rounding of a weighted mean of at most four terms (values ≤ 1, ulp 6e-8: the four
    // products, three sums and the division, which lavapipe computes through a reciprocal,
    // stay within 4e-6; measured 1.1e-6): every pixel of the square is 1, every pixel
    // behind lies within [min, max] of its own surface's texels. The texels are read back at
    // the even pixels, where the upsampling returns the texel itself. Nearest upsampling (the
    // texel of pixel (2⌊x/2⌋, 2⌊y/2⌋)) breaks both where that pixel is across the edge.
    let scene = Scene::from_toml_str(EDGE_SCENE, Path::new("sao edge scene"), Path::new("."))
        .expect("scene");
    let cam = scene.camera;
    let sao = SaoSettings {
        radius_m: 1.0,
        view: true,
        ..Default::default()
    };
    let ao = render(&scene, Some(sao));
    let n = SIZE as i32;
    let front = |p: [i32; 2]| on_front_square(&cam, p);
    let texel = |q: [i32; 2]| {
        let p = [(2 * q[0]).min(n - 1), (2 * q[1]).min(n - 1)];
        (ao[(p[1] * n + p[0]) as usize], front(p))
    };
    let (mut checked, mut front_pixels, mut worst) = (0, 0, 0.0f32);
    let (mut nearest_bleeds, mut min_behind) = (0, 1.0f32);
    for y in 0..n {
        for x in 0..n {
            let p = [x, y];
            let a = ao[(y * n + x) as usize];
            let here = front(p);
            // The texels with a bilinear weight at p: ⌊p/2⌋ + {0, 1} along each odd axis.
            let mut own = Vec::new();
            for oy in 0..=(y & 1) {
                for ox in 0..=(x & 1) {
                    let (v, f) = texel([x / 2 + ox, y / 2 + oy]);
                    if f == here {
                        own.push(v);
                    }
                }
            }
            if !here {
                min_behind = min_behind.min(a);
            }
            // A sliver without a texel of its own surface takes the nearest depth's; none
            // should occur along a straight edge (of two texels symmetric about p, one lies on
            // p's side), and the count is asserted below.
            if own.is_empty() {
                continue;
            }
            checked += 1;
            let lo = own.iter().cloned().fold(f32::INFINITY, f32::min);
            let hi = own.iter().cloned().fold(f32::NEG_INFINITY, f32::max);
            let err = (lo - a).max(a - hi).max(0.0);
            worst = worst.max(err);
            if here {
                front_pixels += 1;
                worst = worst.max((a - 1.0).abs());
            }
            // What nearest upsampling would have read here.
            let (nearest, nf) = texel([x / 2, y / 2]);
            if nf != here && (nearest - a).abs() > 0.05 {
                nearest_bleeds += 1;
            }
        }
    }
    println!(
        "edge: {checked} of {} pixels checked ({front_pixels} on the square), worst excursion \
         {worst:e}, min AO behind {min_behind}, pixels nearest upsampling would bleed: \
         {nearest_bleeds}",
        n * n
    );
    assert!(worst <= 4e-6, "AO bleeds across the edge by {worst}");
    assert!(
        checked >= n * n - 4,
        "{checked} pixels had a texel of their own surface"
    );
    assert!(front_pixels > n * n / 8 && front_pixels < n * n / 2 + n * n / 4);
    // The test has something to bleed: obscured texels behind the edge, and nearest
    // upsampling would carry them across it (or carry the square's 1 onto them).
    assert!(
        min_behind < 0.8,
        "the crease behind the edge is obscured: {min_behind}"
    );
    assert!(
        nearest_bleeds > 0,
        "nearest upsampling would bleed somewhere"
    );
}

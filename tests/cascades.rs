//! Cascaded shadow maps (issue 19; `light::cascade`): a directional light over a large plane,
//! with a long box casting a shadow strip across every split.
//!  - No seam: away from the shadow's edges every pixel is exactly what the single
//!    whole-scene map gives, the closed form ρ/π·E⊥·cos θ where lit and 0 where shadowed, on
//!    both sides of every split.
//!  - Stability: a camera looking straight down moves in steps of one pixel (half a shadow
//!    texel) parallel to the plane; with snapping the shadow mask, moved back by the same
//!    whole pixels, does not change; without snapping it does.
//!
//! The split distances against the scheme's closed form are unit tests in
//! `src/light/cascade.rs`. Every render runs with validation and synchronization validation.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::HdrImage;
use voxgi::light::cascade::{blend_band_m, cascade_range, cascade_splits};
use voxgi::light::ShadowSettings;
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::Scene;

const ALBEDO: f32 = 0.8;
const IRRADIANCE: f32 = 2.0;
/// The sun travels 45° down towards +x.
const SUN: Vec3 = Vec3::new(
    std::f32::consts::FRAC_1_SQRT_2,
    -std::f32::consts::FRAC_1_SQRT_2,
    0.0,
);

/// An axis-aligned box (the scene's caster, a scaled builtin cube).
#[derive(Clone, Copy)]
struct Box3 {
    min: Vec3,
    max: Vec3,
}

impl Box3 {
    /// Entry distance of the ray `o + t d` (t ≥ 0), if it meets the box.
    fn hit(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let inv = d.recip();
        let (a, b) = ((self.min - o) * inv, (self.max - o) * inv);
        let (t0, t1) = (a.min(b).max_element(), a.max(b).min_element());
        (t1 >= t0.max(0.0)).then_some(t0.max(0.0))
    }

    fn toml(&self) -> String {
        let c = (self.min + self.max) * 0.5;
        let s = self.max - self.min;
        format!(
            "[[objects]]\nname = \"rail\"\nbuiltin = \"cube\"\ntranslate = [{}, {}, {}]\n\
             scale = [{}, {}, {}]\nmaterial = {{ albedo = [0.5, 0.5, 0.5] }}\n",
            c.x, c.y, c.z, s.x, s.y, s.z
        )
    }
}

fn scene_toml(camera: &str, rail: &Box3, plane_m: f32) -> String {
    format!(
        "{camera}[[lights]]\nkind = \"directional\"\ndirection = [{}, {}, {}]\n\
         irradiance_w_m2 = [{IRRADIANCE}, {IRRADIANCE}, {IRRADIANCE}]\n\
         [[objects]]\nname = \"plane\"\nbuiltin = \"quad\"\nscale = [{plane_m}, 1.0, {plane_m}]\n\
         material = {{ albedo = [{ALBEDO}, {ALBEDO}, {ALBEDO}] }}\n{}",
        SUN.x,
        SUN.y,
        SUN.z,
        rail.toml()
    )
}

fn scene(toml: &str) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(toml, Path::new("<test scene>"), &dir).expect("test scene parses")
}

fn render(ctx: &voxgi::vk::Context, scene: &Scene, size: u32, shadow: ShadowSettings) -> HdrImage {
    let settings = RenderSettings {
        width: size,
        height: size,
        shadow,
        ..Default::default()
    };
    let out = render_image(ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(ctx);
    out.hdr
}

/// The shadow-free radiance of the plane: ρ/π · E⊥ cos θ, cos θ = −SUN.y.
fn lit_radiance() -> f32 {
    ALBEDO / std::f32::consts::PI * IRRADIANCE * (-SUN.y)
}

fn value(img: &HdrImage, x: u32, y: u32) -> f32 {
    img.data[(y * img.width + x) as usize][1]
}

/// Where the camera ray of pixel (x, y) meets the plane y = 0, unless it misses it or meets
/// the rail first.
fn plane_point(
    scene: &Scene,
    rail: &Box3,
    (x, y, size): (u32, u32, u32),
    plane_half_m: f32,
) -> Option<Vec3> {
    let (a, b) = common::pixel_ray_points(scene, x, y, size);
    let d = (b - a).normalize();
    let t = -a.y / d.y;
    let p = a + d * t;
    if !t.is_finite() || t <= 0.0 || p.x.abs().max(p.z.abs()) > plane_half_m {
        return None;
    }
    match rail.hit(a, d) {
        Some(t_rail) if t_rail < t => None,
        _ => Some(p),
    }
}

/// Whether the plane point p sees the sun past the rail.
fn sunlit(rail: &Box3, p: Vec3) -> bool {
    rail.hit(p, -SUN).is_none()
}

/// Lit (true) or shadowed (false) for every point within `margin_m` of p on the plane, or
/// `None` near the shadow's edge.
fn sure(rail: &Box3, p: Vec3, margin_m: f32) -> Option<bool> {
    let lit = sunlit(rail, p);
    let offsets = [
        (-1.0, 0.0),
        (1.0, 0.0),
        (0.0, -1.0),
        (0.0, 1.0),
        (0.7, 0.7),
        (-0.7, -0.7),
    ];
    offsets
        .iter()
        .all(|(dx, dz)| sunlit(rail, p + Vec3::new(*dx, 0.0, *dz) * margin_m) == lit)
        .then_some(lit)
}

#[test]
fn cascades_leave_no_seam_at_any_split() {
    const SIZE: u32 = 128;
    // A 3 m high rail along +z casts a strip x in [-0.1, 3.1] m (45° sun) the whole way
    // through the camera's depth range, so the shadow and the lit plane cross every split.
    let rail = Box3 {
        min: Vec3::new(-0.1, 0.0, 0.0),
        max: Vec3::new(0.1, 3.0, 40.0),
    };
    // The camera stands on the shadow's side (x > 3.1 m), so it sees the lit plane on its
    // own side and the strip in front of the rail.
    let camera = "[camera]\nposition = [5.0, 2.0, -2.0]\ntarget = [1.5, 0.0, 10.0]\n\
                  fov_y_deg = 50.0\nnear = 0.1\nfar = 100.0\n";
    let s = scene(&scene_toml(camera, &rail, 80.0));
    let single = ShadowSettings {
        cascades: 1,
        ..Default::default()
    };
    let cascaded = ShadowSettings {
        cascades: 4,
        ..Default::default()
    };
    let ctx = common::context();
    let one = render(&ctx, &s, SIZE, single);
    let four = render(&ctx, &s, SIZE, cascaded);
    let (near, far) = cascade_range(&s.camera, &s.aabb_at(0.0));
    let splits = cascade_splits(near, far, 4, cascaded.cascade_lambda);
    // Margin from the shadow's edge: the whole-scene map's texel is the scene's 80√2 m
    // diagonal over 1024 texels at most (11 cm); the PCF kernel reaches r + 1 = 2 texels and
    // the normal offset at most (r + 1/2)√2 ≈ 2.1 texels, 4.1 texels in all (45 cm). 0.7 m.
    let margin_m = 0.7;
    let lit = lit_radiance();
    // Per split: sure-lit and sure-shadowed pixels just before and just after it.
    let mut counts = vec![[[0u32; 2]; 2]; splits.len()];
    let forward = s.camera.forward.normalize();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = plane_point(&s, &rail, (x, y, SIZE), 40.0 - margin_m) else {
                continue;
            };
            let Some(is_lit) = sure(&rail, p, margin_m) else {
                continue;
            };
            let (a, b) = (value(&one, x, y), value(&four, x, y));
            if is_lit {
                assert!(
                    (a - lit).abs() <= 1e-3 * lit,
                    "single map, lit pixel ({x}, {y}) at {p}: {a} vs the closed form {lit}"
                );
                assert_eq!(a, b, "lit pixel ({x}, {y}) at {p}: 1 vs 4 cascades");
            } else {
                assert_eq!(a, 0.0, "single map, shadowed pixel ({x}, {y}) at {p}");
                assert_eq!(b, 0.0, "4 cascades, shadowed pixel ({x}, {y}) at {p}");
            }
            // Which side of which split, within a quarter of the cascade's range.
            let depth = (p - s.camera.position).dot(forward);
            for (i, &split) in splits.iter().enumerate() {
                let w = 0.25 * (split - if i == 0 { 0.0 } else { splits[i - 1] });
                if (depth - split).abs() < w {
                    counts[i][usize::from(depth >= split)][usize::from(is_lit)] += 1;
                }
            }
        }
    }
    println!("splits {splits:?} m; [before, after] x [shadowed, lit] pixels: {counts:?}");
    // The three inner splits lie on the visible plane (the last is the end of the range).
    for (i, c) in counts.iter().enumerate().take(3) {
        assert!(
            c.iter().flatten().all(|&n| n >= 3),
            "split {i} at {:.2} m (band {:.2} m): too few pixels on a side: {c:?}",
            splits[i],
            blend_band_m(&splits, i)
        );
    }
}

/// PCF taps of the default (2r+1)² kernel.
fn kernel_taps() -> i32 {
    let r = ShadowSettings::default().pcf_radius as i32;
    (2 * r + 1) * (2 * r + 1)
}

/// The lit PCF taps of pixel (x, y) of `img` (0 shadowed … kernel_taps() lit).
fn taps(img: &HdrImage, x: u32, y: u32) -> i32 {
    (value(img, x, y) / lit_radiance() * kernel_taps() as f32).round() as i32
}

/// Renders `steps` + 1 frames of a camera straight above the plane, moved by one pixel's
/// footprint along x per frame, and returns per frame the pixels whose shadow (in PCF taps)
/// differs from frame 0's at the same world point, with the count of edge pixels in frame 0.
fn moving_camera_changes(
    ctx: &voxgi::vk::Context,
    snap: bool,
    steps: u32,
) -> (Vec<u32>, u32, Vec<Vec<f32>>) {
    const SIZE: u32 = 96;
    let (height_m, fov_deg) = (6.0f32, 40.0f32);
    // One pixel of the image at the plane.
    let pixel_m = 2.0 * height_m * (0.5 * fov_deg.to_radians()).tan() / SIZE as f32;
    // A 4 m wall at x = -3 m, turned 10° about y so that its shadow's edge (at x ≈ 1 m, the
    // view's middle) runs oblique to the map's texel rows. The camera sees x in
    // 1 ± (6 m - y)·tan 20°, so only the plane: the wall (|x + 3| ≤ 0.5 m over the view's
    // z range) is out of view at every height, and nothing in view has parallax.
    let rail = "[[objects]]\nname = \"wall\"\nbuiltin = \"cube\"\ntranslate = [-3.0, 2.0, 5.0]\n\
                rotate_deg = [0.0, 10.0, 0.0]\nscale = [0.3, 4.0, 20.0]\n\
                material = { albedo = [0.5, 0.5, 0.5] }\n";
    let shadow = ShadowSettings {
        cascades: 4,
        cascade_snap: snap,
        // 128 texels: the cascade's texel is about two pixels, so each step is a fraction of
        // a texel.
        resolution: 128,
        ..Default::default()
    };
    let mut frames = Vec::new();
    let mut splits = Vec::new();
    for k in 0..=steps {
        let cx = 1.0 + k as f32 * pixel_m;
        let camera = format!(
            "[camera]\nposition = [{cx}, {height_m}, 5.0]\ntarget = [{cx}, 0.0, 5.0]\n\
             up = [0.0, 0.0, 1.0]\nfov_y_deg = {fov_deg}\nnear = 0.1\nfar = 100.0\n"
        );
        let toml = format!(
            "{camera}[[lights]]\nkind = \"directional\"\ndirection = [{}, {}, {}]\n\
             irradiance_w_m2 = [{IRRADIANCE}, {IRRADIANCE}, {IRRADIANCE}]\n\
             [[objects]]\nname = \"plane\"\nbuiltin = \"quad\"\nscale = [40.0, 1.0, 40.0]\n\
             material = {{ albedo = [{ALBEDO}, {ALBEDO}, {ALBEDO}] }}\n{rail}",
            SUN.x, SUN.y, SUN.z
        );
        let s = scene(&toml);
        let (near, far) = cascade_range(&s.camera, &s.aabb_at(0.0));
        splits.push(cascade_splits(
            near,
            far,
            shadow.cascades,
            shadow.cascade_lambda,
        ));
        frames.push(render(ctx, &s, SIZE, shadow));
    }
    // The camera looks along -y with up +z, so screen right is -x: moving the camera k pixels
    // along +x shows at pixel (x, y) what frame 0 showed at (x - k, y), exactly (the plane
    // stays at the same view depth, so the depth buffer holds the same values).
    let mut edge = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let t = taps(&frames[0], x, y);
            if t > 0 && t < kernel_taps() {
                edge += 1;
            }
        }
    }
    let changes = (1..=steps)
        .map(|k| {
            let mut n = 0;
            for y in 0..SIZE {
                for x in k..SIZE {
                    if taps(&frames[k as usize], x, y) != taps(&frames[0], x - k, y) {
                        n += 1;
                    }
                }
            }
            n
        })
        .collect();
    (changes, edge, splits)
}

#[test]
fn snapped_cascades_do_not_swim_under_a_moving_camera() {
    let ctx = common::context();
    let steps = 4;
    let (snapped, edge, splits) = moving_camera_changes(&ctx, true, steps);
    // The test's premise: the splits (and with them each cascade's texel size) stay put over
    // the few centimeters the camera moves.
    assert!(
        splits.windows(2).all(|w| w[0] == w[1]),
        "the splits moved with the camera: {splits:?}"
    );
    let (unsnapped, _, _) = moving_camera_changes(&ctx, false, steps);
    println!(
        "edge pixels {edge}; changed pixels per step, snapped {snapped:?}, unsnapped {unsnapped:?}"
    );
    // With snapping a world point is looked up in the same texels in every frame; a pixel can
    // change only where float rounding of its position (about 1e-6 m against 0.1 m texels)
    // carries a tap across a texel boundary: far below one pixel per frame in expectation.
    // Bound: 1% of the edge pixels (at least 1).
    let bound = (edge / 100).max(1);
    assert!(edge >= 50, "the shadow edge is in view: {edge} pixels");
    assert!(
        snapped.iter().all(|&n| n <= bound),
        "snapped cascades: {snapped:?} pixels changed, bound {bound}"
    );
    // Without snapping the texel grid slides half a texel per step over the world, so the
    // stair-stepped edge moves: a good share of the edge pixels change.
    assert!(
        unsnapped.iter().any(|&n| n > 10 * bound),
        "without snapping the shadow should swim: {unsnapped:?} changed pixels, edge {edge}"
    );
}

#[test]
fn shadow_texel_view_matches_the_closed_form() {
    // A camera straight down at h = 4 m over the plane, the sun 45° off the vertical, one
    // whole-scene orthographic map (its texel d_s is the view's footprint, meters). At the
    // image's center the view ray is the plane's normal (cos α_i = 1, view depth h), so
    // d_i = d_s · pixel_scale / (cos α_s · h), pixel_scale = H / (2 tan(fov_y/2)).
    const SIZE: u32 = 64;
    let (h, fov_deg) = (4.0f32, 40.0f32);
    let rail = Box3 {
        min: Vec3::new(-3.1, 0.0, -1.0),
        max: Vec3::new(-3.0, 0.5, 1.0),
    };
    let camera = format!(
        "[camera]\nposition = [0.0, {h}, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n\
         fov_y_deg = {fov_deg}\nnear = 0.1\nfar = 100.0\n"
    );
    let s = scene(&scene_toml(&camera, &rail, 20.0));
    let shadow = ShadowSettings {
        cascades: 1,
        ..Default::default()
    };
    let (views, _) = voxgi::light::shadow_views(&s, 0.0, &shadow);
    let d_s = views[0].texel_footprint;
    let pixel_scale = SIZE as f32 / (2.0 * (0.5 * fov_deg.to_radians()).tan());
    let want = d_s * pixel_scale / (-SUN.y * h);
    let ctx = common::context();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        shadow,
        debug: Some(voxgi::voxel::debug_view::DebugSettings {
            view: voxgi::voxel::debug_view::DebugView::ShadowTexels,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = render_image(&ctx, &s, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    // The four pixels around the center: their rays are off the normal by half a pixel
    // (tan = 0.5 / pixel_scale), which changes cos α_i and the depth by under 1e-4.
    for (x, y) in [(31, 31), (32, 31), (31, 32), (32, 32)] {
        let p = out.hdr.data[(y * SIZE + x) as usize];
        assert!(
            (p[0] - want).abs() <= 1e-3 * want,
            "pixel ({x}, {y}): d_i {} px, closed form {want} px",
            p[0]
        );
        assert!(
            (p[1] - d_s).abs() <= 1e-6 * d_s,
            "texel {} m vs {d_s} m",
            p[1]
        );
    }
    println!("{}", out.debug_description.unwrap_or_default());
}

/// A compact scene seen from inside (a 4 m plane, the camera 1.5 m over its edge looking
/// across it): the cascades' range ends where the scene does, about 4 m away, and the far
/// slices' bounding spheres are wider than the whole scene, so their texels are coarser than
/// the whole-scene map's. Those cascades are dropped (`cascade_views`): every lit pixel is
/// shaded by a texel no larger than the whole-scene map's, and four cascades never leave more
/// pixels above one pixel's size than the single map does.
#[test]
fn cascades_coarser_than_the_whole_map_are_dropped() {
    const SIZE: u32 = 64;
    let rail = Box3 {
        min: Vec3::new(-0.2, 0.0, 0.0),
        max: Vec3::new(0.2, 0.3, 0.1),
    };
    let camera = "[camera]\nposition = [0.0, 1.5, -2.0]\ntarget = [0.0, 0.0, 0.5]\n\
                  fov_y_deg = 60.0\nnear = 0.05\nfar = 100.0\n";
    let s = scene(&scene_toml(camera, &rail, 4.0));
    let shadow = |cascades| ShadowSettings {
        cascades,
        ..Default::default()
    };
    // The library's choice: the whole-scene map's texel against the cascades' texels.
    let (views, _) = voxgi::light::shadow_views(&s, 0.0, &shadow(4));
    let whole_m = views[0].texel_footprint;
    let aabb = s.aabb_at(0.0);
    let all =
        voxgi::light::cascade::cascade_views(&s.lights, &s.camera, 1.0, &aabb, &shadow(4), |_| {
            f32::INFINITY
        });
    let kept =
        voxgi::light::cascade::cascade_views(&s.lights, &s.camera, 1.0, &aabb, &shadow(4), |_| {
            whole_m
        });
    let count =
        |sets: &[(usize, Vec<voxgi::light::ShadowView>)]| sets.first().map_or(0, |s| s.1.len());
    assert_eq!(count(&all), 4);
    assert!(
        (1..4).contains(&count(&kept)),
        "some cascades are coarser than the {whole_m} m whole-scene texel, some finer: kept {}",
        count(&kept)
    );

    let ctx = common::context();
    let texels = |cascades| {
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            shadow: shadow(cascades),
            debug: Some(voxgi::voxel::debug_view::DebugSettings {
                view: voxgi::voxel::debug_view::DebugView::ShadowTexels,
                ..Default::default()
            }),
            ..Default::default()
        };
        let out = render_image(&ctx, &s, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        out.hdr
    };
    let (one, four) = (texels(1), texels(4));
    for p in four.data.iter().filter(|p| p[0] > 0.0) {
        assert!(
            p[1] <= whole_m * (1.0 + 1e-6),
            "a {} m texel, whole map {whole_m} m",
            p[1]
        );
    }
    let above_one_px = |img: &HdrImage| img.data.iter().filter(|p| p[0] > 1.0).count();
    assert!(
        above_one_px(&four) <= above_one_px(&one),
        "4 cascades: {} pixels above 1 px, 1 map: {}",
        above_one_px(&four),
        above_one_px(&one)
    );
}

/// `--shadow-resolution auto` picks the smallest power of two whose texels stay under a pixel
/// for 95% of the lit pixels, from one probe frame at 1024², assuming every texel scales as
/// 1/R. Checked on the GPU at the pick: the 95th percentile of the perspective d_i is at most
/// one pixel there, and above one at half the pick. A camera 4 m over the plane needs a finer
/// map than one 32 m over it (d_i ∝ 1/view depth).
#[test]
fn automatic_shadow_resolution_is_the_smallest_that_keeps_texels_under_a_pixel() {
    const SIZE: u32 = 96;
    let rail = Box3 {
        min: Vec3::new(-0.5, 0.0, -0.5),
        max: Vec3::new(0.5, 1.0, 0.5),
    };
    let ctx = common::context();
    let q95 = |img: &HdrImage| {
        let mut d: Vec<f32> = img.data.iter().map(|p| p[0]).filter(|&x| x > 0.0).collect();
        d.sort_by(f32::total_cmp);
        d[((0.95 * d.len() as f64).ceil() as usize).clamp(1, d.len()) - 1]
    };
    let perspective_texels = |s: &Scene, resolution: u32| {
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            shadow: ShadowSettings {
                resolution,
                cascades: 1,
                ..Default::default()
            },
            debug: Some(voxgi::voxel::debug_view::DebugSettings {
                view: voxgi::voxel::debug_view::DebugView::ShadowTexelsPerspective,
                ..Default::default()
            }),
            ..Default::default()
        };
        let out = render_image(&ctx, s, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        q95(&out.hdr)
    };
    let mut picks = Vec::new();
    for h in [4.0f32, 32.0] {
        let camera = format!(
            "[camera]\nposition = [0.0, {h}, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n\
             fov_y_deg = 40.0\nnear = 0.1\nfar = 100.0\n"
        );
        let s = scene(&scene_toml(&camera, &rail, 40.0));
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            shadow: ShadowSettings {
                cascades: 1,
                auto_resolution: true,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &s, &settings).expect("renders");
        common::assert_no_validation_messages(&ctx);
        let pick = out.auto_shadow.expect("auto was asked for");
        let at_pick = perspective_texels(&s, pick.resolution);
        assert!(
            at_pick <= 1.0 + 1e-3,
            "h {h}: {pick:?}, 95th percentile {at_pick} px"
        );
        let at_half = perspective_texels(&s, pick.resolution / 2);
        assert!(
            at_half > 1.0,
            "h {h}: {pick:?} is not the smallest: {at_half} px at half"
        );
        picks.push(pick.resolution);
    }
    assert!(
        picks[0] > picks[1],
        "close-up {} vs far {}",
        picks[0],
        picks[1]
    );
}

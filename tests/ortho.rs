//! The orthographic camera (issue 17) through the frame: sizes on screen from the closed form
//! (size / view height × image height, at any depth), the view vector of shading (constant
//! −forward: a flat GGX floor under a sun has one radiance everywhere, the BRDF's), the
//! G-buffer distance view (the view depth), the GI methods and post passes with validation
//! clean, and the configurations it refuses (screen-space GI, stereo) by name. Validation and
//! synchronization validation are on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::gi::GiMethod;
use voxgi::render::{render_image, RenderError, RenderSettings};
use voxgi::scene::{Projection, Scene};
use voxgi::voxel::debug_view::{DebugSettings, DebugView};

const SIZE: u32 = 64;
/// The orthographic view's height in meters: 64 px / 2 m = 32 px per meter.
const VIEW_HEIGHT_M: f32 = 2.0;
/// The emissive patches' side, meters: 0.5 · 32 = 16 pixels at any depth.
const PATCH_M: f32 = 0.5;

/// Camera 5 m above the origin looking down; two emissive patches facing it, one at depth 2 m
/// (x = −0.5) and one at depth 5 m (x = +0.5), on either side of the image's centre column.
/// No lights: only the patches are bright.
const PATCHES: &str = r#"
[camera]
position = [0.0, 5.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov_y_deg = 60.0
projection = "orthographic"
ortho_height_m = 2.0
near = 0.05
far = 10.0

[[objects]]
name = "near_patch"
builtin = "quad"
translate = [-0.5, 3.0, 0.0]
scale = [0.5, 1.0, 0.5]
material = { albedo = 0.0, emission_w_sr_m2 = [5.0, 5.0, 5.0] }

[[objects]]
name = "far_patch"
builtin = "quad"
translate = [0.5, 0.0, 0.0]
scale = [0.5, 1.0, 0.5]
material = { albedo = 0.0, emission_w_sr_m2 = [5.0, 5.0, 5.0] }
"#;

fn scene(toml: &str) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(toml, Path::new("<ortho test scene>"), &dir).expect("scene parses")
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        ..Default::default()
    }
}

/// Width and height in pixels of the bounding box of the pixels in columns `cols` where
/// `inside` holds.
fn extent(
    img: &voxgi::eval::HdrImage,
    cols: std::ops::Range<u32>,
    inside: impl Fn([f32; 3]) -> bool,
) -> (u32, u32) {
    let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
    for y in 0..img.height {
        for x in cols.clone() {
            if inside(img.data[(y * img.width + x) as usize]) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x + 1), y0.min(y), y1.max(y + 1));
            }
        }
    }
    assert!(x0 < x1, "nothing in columns {cols:?}");
    (x1 - x0, y1 - y0)
}

#[test]
fn sizes_on_screen_follow_the_view_height_at_any_depth() {
    let ctx = common::context();
    let mut s = scene(PATCHES);
    assert_eq!(
        (s.camera.projection, s.camera.ortho_height_m),
        (Projection::Orthographic, VIEW_HEIGHT_M)
    );
    let bright = |p: [f32; 3]| p[0] > 2.5;
    // right() = forward × up = (0,−1,0) × (0,0,1) = −x: the near patch (x = −0.5) is on the
    // right half of the image, the far one (x = +0.5) on the left.
    let half = SIZE / 2;
    let img = render_image(&ctx, &s, &settings()).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    // 0.5 m / 2 m × 64 px = 16 px. An edge at a fractional pixel position covers the pixel
    // centres of a half-open span of exactly its length, so each side is 16 pixels (±1 for
    // a rasterizer tie exactly at a centre).
    let expected = (PATCH_M / VIEW_HEIGHT_M * SIZE as f32).round() as i64;
    for (what, cols) in [("near", half..SIZE), ("far", 0..half)] {
        let (w, h) = extent(&img, cols, bright);
        assert!(
            (w as i64 - expected).abs() <= 1 && (h as i64 - expected).abs() <= 1,
            "{what} patch {w}×{h} px, expected {expected}²"
        );
    }
    // The same scene through the 60° pinhole: the patches' sizes differ by their depths'
    // ratio, 5/2 (13.9 px and 5.5 px), so the check above can tell the projections apart.
    s.camera.projection = Projection::Perspective;
    let img = render_image(&ctx, &s, &settings()).expect("renders").hdr;
    let (near_w, _) = extent(&img, half..SIZE, bright);
    let (far_w, _) = extent(&img, 0..half, bright);
    assert!(
        near_w >= 2 * far_w,
        "perspective: near {near_w} px, far {far_w} px"
    );
}

#[test]
fn the_distance_view_shows_the_view_depth() {
    let ctx = common::context();
    let s = scene(PATCHES);
    let settings = RenderSettings {
        debug: Some(DebugSettings {
            view: DebugView::GbufferDistance,
            ..Default::default()
        }),
        ..settings()
    };
    let img = render_image(&ctx, &s, &settings).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    // Every pixel of a patch facing the camera has its depth, 2 m and 5 m (under
    // perspective the distance would grow towards the patch's corners: by 3% at 5 m).
    let half = SIZE / 2;
    for (cols, depth) in [(half..SIZE, 2.0f32), (0..half, 5.0)] {
        let mut n = 0;
        for y in 0..SIZE {
            for x in cols.clone() {
                let v = img.data[(y * SIZE + x) as usize][0];
                if v > 0.0 {
                    assert!(
                        (v - depth).abs() < 1e-3,
                        "({x}, {y}): {v} m, expected {depth}"
                    );
                    n += 1;
                }
            }
        }
        assert!(n >= 15 * 15, "{n} pixels at {depth} m");
    }
}

/// A GGX metal floor lit by a sun, seen at 45° through an orthographic camera: every pixel has
/// the same normal, light direction and (orthographic) view direction, so every floor pixel
/// has the radiance f(wi, wo)·E·cos θ, f from the CPU twin `scene::ggx_brdf`. The shadow maps
/// see nothing above the floor (visibility 1) — with the sun's cascades, which pick their
/// slice by the pixel's view depth.
#[test]
fn a_flat_glossy_floor_has_one_radiance_under_orthographic_projection() {
    let ctx = common::context();
    let toml = r#"
[camera]
position = [0.0, 3.0, -3.0]
target = [0.0, 0.0, 0.0]
projection = "orthographic"
ortho_height_m = 1.5
near = 0.1
far = 20.0

[[lights]]
kind = "directional"
direction = [0.3, -1.0, 0.5]
irradiance_w_m2 = [2.0, 2.0, 2.0]

[[objects]]
name = "floor"
builtin = "quad"
scale = [8.0, 1.0, 8.0]
material = { albedo = [0.9, 0.6, 0.3], roughness = 0.5, metallic = 1.0 }
"#;
    let mut s = scene(toml);
    let (base, ggx) = {
        let m = &s.materials[s.objects[0].materials[0]];
        (m.albedo, m.ggx.expect("a GGX material"))
    };
    let n = Vec3::Y;
    let wi = -Vec3::new(0.3, -1.0, 0.5).normalize();
    let wo = -s.camera.forward;
    let expected = voxgi::scene::ggx_brdf(base, ggx, n, wi, wo) * 2.0 * n.dot(wi);
    for cascades in [1, 4] {
        let mut settings = settings();
        settings.shadow.cascades = cascades;
        let img = render_image(&ctx, &s, &settings).expect("renders").hdr;
        common::assert_no_validation_messages(&ctx);
        for (i, p) in img.data.iter().enumerate() {
            let got = Vec3::from_array(*p);
            assert!(
                (got - expected).abs().max_element() <= 2e-3 * expected.max_element(),
                "{cascades} cascade(s), pixel {i}: {got} vs {expected}"
            );
        }
    }
    // Through a pinhole the view direction changes across the floor, and so does the
    // radiance (the test above could not pass by accident).
    s.camera.projection = Projection::Perspective;
    s.camera.fov_y_deg = 40.0;
    let img = render_image(&ctx, &s, &settings()).expect("renders").hdr;
    let red: Vec<f32> = img.data.iter().map(|p| p[0]).collect();
    let (lo, hi) = red
        .iter()
        .fold((f32::MAX, 0.0f32), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi > 1.1 * lo, "perspective floor from {lo} to {hi}");
}

/// Every voxel GI method (with SAO on the hemisphere method) and the post chain render the
/// Cornell box through an orthographic camera with validation clean, adding light to the
/// direct image.
#[test]
fn gi_methods_and_post_passes_render_orthographic() {
    let ctx = common::context();
    let mut s = voxgi::scene::load_scene_arg(Some("cornell")).expect("built-in");
    s.camera.projection = Projection::Orthographic;
    s.camera.ortho_height_m = 0.6;
    let mean = |img: &voxgi::eval::HdrImage| {
        img.data.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / img.data.len() as f32
    };
    let mut direct = settings();
    direct.gi.method = GiMethod::None;
    direct.post.taa = Some(Default::default());
    direct.post.taa.as_mut().expect("set").frames = 2;
    direct.post.bloom = Some(0.1);
    let base = mean(&render_image(&ctx, &s, &direct).expect("renders").hdr);
    common::assert_no_validation_messages(&ctx);
    assert!(base > 0.0 && base.is_finite(), "direct mean {base}");
    for method in [GiMethod::Hemisphere, GiMethod::Pathtrace, GiMethod::Vpl] {
        let mut settings = settings();
        settings.gi.method = method;
        settings.gi.rays = 4;
        settings.gi.accumulate_frames = 1;
        if method == GiMethod::Hemisphere {
            settings.gi.sao = Some(Default::default());
        }
        let img = render_image(&ctx, &s, &settings).expect("renders").hdr;
        common::assert_no_validation_messages(&ctx);
        let m = mean(&img);
        assert!(
            m.is_finite() && m > 1.02 * base,
            "{method:?}: mean {m} against direct {base}"
        );
    }
}

#[test]
fn screen_space_gi_and_stereo_are_refused_by_name() {
    let ctx = common::context();
    let s = scene(PATCHES);
    let mut settings = settings();
    settings.gi.method = GiMethod::Ssgi;
    let Err(e) = render_image(&ctx, &s, &settings) else {
        panic!("--gi ssgi rendered orthographic");
    };
    assert!(
        matches!(
            e,
            RenderError::Orthographic {
                what: "--gi ssgi",
                ..
            }
        ),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("--projection perspective") && text.contains("--gi"),
        "{text}"
    );
    let stereo = voxgi::render::StereoSettings {
        mode: voxgi::post::StereoMode::SideBySide,
        rig: Default::default(),
        path: voxgi::render::StereoPath::TwoPass,
    };
    let Err(e) = voxgi::render::render_stereo(&ctx, &s, &self::settings(), stereo) else {
        panic!("stereo rendered orthographic");
    };
    assert!(
        matches!(
            e,
            RenderError::Orthographic {
                what: "--stereo",
                ..
            }
        ),
        "{e}"
    );
    common::assert_no_validation_messages(&ctx);
}

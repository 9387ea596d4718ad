//! Stereo output: the eyes' disparity in a rendered pair against the off-axis frusta's closed
//! form, and every packing of `stereo_pack` read back pixel by pixel against its definition
//! (which eye lands in which texel; the anaglyph matrices as published). Validation and
//! synchronization validation are on.

mod common;

use std::path::Path;
use voxgi::post::StereoMode;
use voxgi::render::{
    eye_scene, render_image, render_stereo, stereo_pack, RenderSettings, StereoPath, StereoSettings,
};
use voxgi::scene::{Eye, Scene, StereoRig};

const SIZE: u32 = 64;

/// Camera 3 m above a black floor, looking down; an emissive patch on the floor (3 m away, at
/// the convergence distance) and a small emissive patch 1 m from the camera. No lights: only
/// the patches are bright, so each patch's pixels are where the eye sees it.
const SCENE: &str = r#"
[camera]
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov_y_deg = 60.0
near = 0.05
far = 10.0

[[objects]]
name = "floor"
builtin = "quad"
scale = [2.0, 1.0, 2.0]
material = { albedo = 0.0 }

[[objects]]
name = "far_patch"
builtin = "quad"
translate = [0.6, 0.001, 0.0]
scale = [0.4, 1.0, 0.4]
material = { albedo = 0.0, emission_w_sr_m2 = [5.0, 5.0, 5.0] }

[[objects]]
name = "near_patch"
builtin = "quad"
translate = [-0.3, 2.0, 0.0]
scale = [0.15, 1.0, 0.15]
material = { albedo = 0.0, emission_w_sr_m2 = [5.0, 5.0, 5.0] }
"#;

fn scene() -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(SCENE, Path::new("<stereo test scene>"), &dir).expect("scene parses")
}

/// Mean x (pixel centres) of the bright pixels of an RGBA8 image in columns `cols`.
fn centroid_x(ldr: &[u8], w: u32, cols: std::ops::Range<u32>) -> f32 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in 0..SIZE {
        for x in cols.clone() {
            if ldr[((y * w + x) * 4) as usize] > 128 {
                sum += x as f32 + 0.5;
                n += 1.0;
            }
        }
    }
    assert!(n > 0.0, "no bright pixel in columns {cols:?}");
    sum / n
}

#[test]
fn rendered_pair_has_the_closed_form_disparity_and_packs_side_by_side() {
    let ctx = common::context();
    let scene = scene();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        ..Default::default()
    };
    let rig = StereoRig {
        separation_m: 0.2,
        convergence_m: 3.0,
    };
    let mode = StereoMode::SideBySideFull;
    for path in [StereoPath::OneFrame, StereoPath::TwoPass] {
        let stereo = StereoSettings { mode, rig, path };
        let out = render_stereo(&ctx, &scene, &settings, stereo).expect("stereo renders");
        common::assert_no_validation_messages(&ctx);
        assert_eq!((out.path, &out.fallback), (path, &None));
        check_disparity_and_side_by_side(&scene, rig, &out);
    }
}

fn check_disparity_and_side_by_side(
    scene: &Scene,
    rig: StereoRig,
    out: &voxgi::render::StereoOutput,
) {
    // right() = forward × up = (0,-1,0) × (0,0,1) = -x: the near patch (x = -0.3) is on the
    // right of the image, the far patch (x = 0.6) on the left; the centre column splits them.
    let half = SIZE / 2;
    let (l, r) = (&out.left.ldr, &out.right.ldr);
    let far_d = centroid_x(r, SIZE, 0..half) - centroid_x(l, SIZE, 0..half);
    let near_d = centroid_x(r, SIZE, half..SIZE) - centroid_x(l, SIZE, half..SIZE);
    // d = f e (1/c − 1/z), f = 32 / tan 30° = 55.4 px: 0 at z = c = 3 m (the far patch, 2.999 m
    // away: −0.002 px), and 55.4 · 0.2 · (1/3 − 1) = −7.39 px at z = 1 m. A patch's centroid
    // is off by at most half a pixel per edge quantization in each eye, so 0.75 px bounds the
    // difference.
    let expected_near = rig.disparity_px(&scene.camera, SIZE, 1.0);
    assert!((expected_near + 7.39).abs() < 0.01, "{expected_near}");
    assert!(
        far_d.abs() < 0.75,
        "far patch disparity {far_d} px, expected 0"
    );
    assert!(
        (near_d - expected_near).abs() < 0.75,
        "near patch disparity {near_d} px, expected {expected_near}"
    );
    // Side-by-side-full: left eye in the left half, right eye in the right half, unchanged.
    assert_eq!(out.packed_size, (2 * SIZE, SIZE));
    for y in 0..SIZE as usize {
        let row = &out.packed[y * 8 * SIZE as usize..(y + 1) * 8 * SIZE as usize];
        let eye_row = y * 4 * SIZE as usize..(y + 1) * 4 * SIZE as usize;
        assert_eq!(
            &row[..4 * SIZE as usize],
            &l[eye_row.clone()],
            "row {y} left"
        );
        assert_eq!(&row[4 * SIZE as usize..], &r[eye_row], "row {y} right");
    }
}

/// Largest difference of two images' channels, in 8-bit steps and relative radiance.
fn max_difference(a: &voxgi::render::RenderOutput, b: &voxgi::render::RenderOutput) -> (u8, f32) {
    let ldr = a.ldr.iter().zip(&b.ldr).map(|(x, y)| x.abs_diff(*y)).max();
    let hdr = a.hdr.data.iter().zip(&b.hdr.data).flat_map(|(x, y)| {
        (0..3).map(move |c| (x[c] - y[c]).abs() / x[c].abs().max(y[c].abs()).max(1e-6))
    });
    (ldr.unwrap_or(0), hdr.fold(0.0, f32::max))
}

/// The one-frame pair (world-space passes once, both eyes' G-buffers in two-layer images,
/// screen-space passes per layer) equals the two-pass pair and each eye's mono render: both
/// paths draw the same triangles with the same matrices and run the same shaders on the same
/// inputs, so nothing may differ (bit-exact; the GI methods' random sequences are seeded by the
/// frame count, which both paths restart per eye). The multiview pair (both eyes' G-buffer in
/// one Vulkan multiview pass) equals the one-frame pair too: the same triangles through the
/// same vertex and fragment code, only drawn as two views of one draw. Cornell's walls cross
/// the viewport edges, so the driver clips triangles in both views of a draw (lavapipe before
/// Mesa 23.0.4 put 479 of the right eye's 4096 pixels into the left eye's layer here without
/// `render::MultiviewDefect`'s workaround).
#[test]
fn one_frame_pair_equals_two_pass_and_multiview_pairs_and_mono_eyes() {
    let ctx = common::context();
    let scene = voxgi::scene::builtin("cornell").expect("cornell");
    let rig = StereoRig {
        separation_m: 0.1,
        convergence_m: 1.0,
    };
    let mode = StereoMode::SideBySideFull;
    for gi in [voxgi::gi::GiMethod::None, voxgi::gi::GiMethod::Hemisphere] {
        let mut settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            ..Default::default()
        };
        settings.gi.method = gi;
        let render = |path| {
            let stereo = StereoSettings { mode, rig, path };
            let out = render_stereo(&ctx, &scene, &settings, stereo).expect("stereo renders");
            assert_eq!((out.path, &out.fallback), (path, &None));
            out
        };
        let one = render(StereoPath::OneFrame);
        let two = render(StereoPath::TwoPass);
        let multiview = render(StereoPath::Multiview);
        let mono_left = render_image(&ctx, &eye_scene(&scene, rig, Eye::Left), &settings)
            .expect("left eye renders");
        let mono_right = render_image(&ctx, &eye_scene(&scene, rig, Eye::Right), &settings)
            .expect("right eye renders");
        common::assert_no_validation_messages(&ctx);
        for (name, a, b) in [
            ("one-frame vs two-pass, left", &one.left, &two.left),
            ("one-frame vs two-pass, right", &one.right, &two.right),
            ("one-frame vs multiview, left", &one.left, &multiview.left),
            (
                "one-frame vs multiview, right",
                &one.right,
                &multiview.right,
            ),
            ("one-frame vs mono, left", &one.left, &mono_left),
            ("one-frame vs mono, right", &one.right, &mono_right),
        ] {
            assert_eq!(max_difference(a, b), (0, 0.0), "{gi:?}: {name}");
        }
        assert_eq!(one.packed, two.packed, "{gi:?}");
        assert_eq!(one.packed, multiview.packed, "{gi:?}");
    }
}

/// Lit patches at three depths, all inside both eyes' view (camera as in [`SCENE`]: 3 m above
/// the plate, looking down, 60° field of view, so the view at the plate's depth is ±1.73 m
/// wide; the eyes' images of the plate, at the convergence distance, coincide): no triangle
/// crosses a viewport edge in either eye.
const INSIDE: &str = r#"
[camera]
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov_y_deg = 60.0
near = 0.05
far = 10.0

[[lights]]
kind = "point"
position = [0.3, 2.5, 0.4]
intensity_w_sr = [4.0, 4.0, 4.0]

[[objects]]
name = "plate"
builtin = "quad"
scale = [2.0, 1.0, 2.0]
material = { albedo = 0.7 }

[[objects]]
name = "tilted"
builtin = "quad"
translate = [0.4, 1.0, -0.3]
rotate_deg = [30.0, 20.0, 0.0]
scale = [0.6, 1.0, 0.5]
material = { albedo = [0.8, 0.3, 0.2] }

[[objects]]
name = "near_patch"
builtin = "quad"
translate = [-0.3, 2.0, 0.2]
scale = [0.15, 1.0, 0.15]
material = { albedo = 0.0, emission_w_sr_m2 = [5.0, 5.0, 5.0] }
"#;

/// [`INSIDE`] with its plate grown from 2 m to 6 m: the plate's edges (±3 m) lie beyond
/// both eyes' view at its depth (±1.73 m, shifted by at most the eye separation), so the
/// driver clips its triangles in both views of its draw.
fn clipped_scene() -> Scene {
    let plate = "scale = [2.0, 1.0, 2.0]";
    assert_eq!(INSIDE.matches(plate).count(), 1, "the plate's scale");
    let toml = INSIDE.replace(plate, "scale = [6.0, 1.0, 6.0]");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(&toml, Path::new("<multiview test scene>"), &dir).expect("scene parses")
}

/// The multiview G-buffer (both eyes in one pass, `gl_ViewIndex` picking the eye's matrices
/// and writing its layer) gives the one-frame pair bit for bit, with triangles that the driver
/// clips in both views of a draw ([`clipped_scene`]). Lavapipe before Mesa 23.0.4 rasterizes
/// view 1's clipped triangles into layer 0 (`render::MultiviewDefect`); without the
/// workaround this scene's right eye lost the whole plate there. Both eyes must also differ
/// from each other, so an eye's matrices or frame constants taken for the other's would fail.
#[test]
fn multiview_pair_equals_one_frame_pair_with_clipped_triangles() {
    let ctx = common::context();
    let scene = clipped_scene();
    let rig = StereoRig {
        separation_m: 0.2,
        convergence_m: 3.0,
    };
    let mode = StereoMode::SideBySideFull;
    for gi in [voxgi::gi::GiMethod::None, voxgi::gi::GiMethod::Hemisphere] {
        let mut settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            ..Default::default()
        };
        settings.gi.method = gi;
        let render = |path| {
            let stereo = StereoSettings { mode, rig, path };
            let out = render_stereo(&ctx, &scene, &settings, stereo).expect("stereo renders");
            assert_eq!((out.path, &out.fallback), (path, &None), "{gi:?}");
            out
        };
        let one = render(StereoPath::OneFrame);
        let multiview = render(StereoPath::Multiview);
        common::assert_no_validation_messages(&ctx);
        assert_eq!(
            max_difference(&multiview.left, &one.left),
            (0, 0.0),
            "{gi:?} left"
        );
        assert_eq!(
            max_difference(&multiview.right, &one.right),
            (0, 0.0),
            "{gi:?} right"
        );
        // The eyes differ (the near patch moves by its disparity, 55.4 · 0.2 · (1/3 − 1) =
        // −7.4 px), and the plate crosses every viewport edge: the image's corners, outside
        // a 2 m plate's image (±1 m of ±1.73 m), are lit plate in both eyes.
        assert_ne!(one.left.ldr, one.right.ldr, "{gi:?}");
        for (eye, out) in [("left", &one.left), ("right", &one.right)] {
            for (x, y) in [(0, 0), (SIZE - 1, 0), (0, SIZE - 1), (SIZE - 1, SIZE - 1)] {
                let p = texel(&out.ldr, SIZE, x, y);
                assert!(p[0] > 0, "{gi:?}: {eye} eye's corner ({x}, {y}) is {p:?}");
            }
        }
    }
}

/// Stereo with `--taa`: each eye keeps its own history and its own jitter sequence (a second
/// `PostPasses`, its jitter written into the right eye's frame constants), so the one-frame
/// pair after N jittered frames is each eye's mono `--taa` render after N frames, bit for bit
/// (same sequence, same history, same shaders; a history or jitter shared between the eyes
/// would mix the left eye into the right). The multiview pair equals the one-frame pair on
/// [`clipped_scene`] (triangles clipped in both views). TAA must also
/// have changed the image (jittered frames blended), or the comparison would prove nothing.
#[test]
fn stereo_taa_pair_equals_each_eyes_mono_taa_render() {
    let ctx = common::context();
    let mut settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        ..Default::default()
    };
    settings.post.taa = Some(voxgi::post::TaaSettings {
        history_weight: 0.9,
        frames: 6,
        ..Default::default()
    });
    let mode = StereoMode::SideBySideFull;
    let cornell = voxgi::scene::builtin("cornell").expect("cornell");
    let clipped = clipped_scene();
    let rig = StereoRig {
        separation_m: 0.1,
        convergence_m: 1.0,
    };
    let render = |scene: &Scene, settings: &RenderSettings, path| {
        let stereo = StereoSettings { mode, rig, path };
        let out = render_stereo(&ctx, scene, settings, stereo).expect("stereo renders");
        assert_eq!((out.path, &out.fallback), (path, &None));
        out
    };
    let one = render(&cornell, &settings, StereoPath::OneFrame);
    for (eye, got) in [(Eye::Left, &one.left), (Eye::Right, &one.right)] {
        let mono = render_image(&ctx, &eye_scene(&cornell, rig, eye), &settings)
            .expect("mono eye renders");
        assert_eq!(max_difference(got, &mono), (0, 0.0), "{eye:?} eye with TAA");
    }
    let plain = RenderSettings {
        post: Default::default(),
        ..settings.clone()
    };
    let still = render(&cornell, &plain, StereoPath::OneFrame);
    assert_ne!(
        still.right.ldr, one.right.ldr,
        "TAA left the right eye unchanged"
    );
    let one = render(&clipped, &settings, StereoPath::OneFrame);
    let multiview = render(&clipped, &settings, StereoPath::Multiview);
    assert_eq!(
        max_difference(&multiview.left, &one.left),
        (0, 0.0),
        "multiview left"
    );
    assert_eq!(
        max_difference(&multiview.right, &one.right),
        (0, 0.0),
        "multiview right"
    );
    common::assert_no_validation_messages(&ctx);
}

/// Two distinct eye images of `w`×`h`: every texel a different colour, the eyes different
/// everywhere (so a swapped eye or texel cannot go unnoticed).
fn eyes(w: u32, h: u32) -> (Vec<u8>, Vec<u8>) {
    let make = |seed: u32| {
        (0..w * h)
            .flat_map(|i| {
                let v = i.wrapping_mul(2654435761).wrapping_add(seed) >> 8;
                [
                    (v & 255) as u8,
                    ((v >> 8) & 255) as u8,
                    ((v >> 16) & 255) as u8,
                    255,
                ]
            })
            .collect::<Vec<u8>>()
    };
    (make(0), make(0x9e37_79b9))
}

fn texel(img: &[u8], w: u32, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * w + x) * 4) as usize;
    [img[i], img[i + 1], img[i + 2], 255]
}

/// The eye texel under the centre of packed texel `o` when `n` eye texels are shown in `m`.
fn squeezed(o: u32, m: u32, n: u32) -> u32 {
    (((o as f64 + 0.5) * n as f64 / m as f64).floor() as u32).min(n - 1)
}

/// Which eye (true: left) and which of its texels each spatial packing puts at (x, y), written
/// from the packings' definitions.
fn spatial_source(mode: StereoMode, (w, h): (u32, u32), x: u32, y: u32) -> (bool, u32, u32) {
    let (wl, hl) = (w.div_ceil(2), h.div_ceil(2));
    match mode {
        StereoMode::SideBySide if x < wl => (true, squeezed(x, wl, w), y),
        StereoMode::SideBySide => (false, squeezed(x - wl, w - wl, w), y),
        StereoMode::SideBySideFull => (x < w, x % w, y),
        StereoMode::TopBottom if y < hl => (true, x, squeezed(y, hl, h)),
        StereoMode::TopBottom => (false, x, squeezed(y - hl, h - hl, h)),
        StereoMode::RowInterleaved => (y.is_multiple_of(2), x, y),
        StereoMode::ColumnInterleaved => (x.is_multiple_of(2), x, y),
        StereoMode::Checkerboard => ((x + y).is_multiple_of(2), x, y),
        _ => unreachable!("{mode:?} is an anaglyph"),
    }
}

#[test]
fn spatial_packings_put_each_eye_where_their_definition_says() {
    let ctx = common::context();
    // Odd sizes: the left eye gets the larger half of a halved axis.
    let size = (9, 7);
    let (l, r) = eyes(size.0, size.1);
    for mode in [
        StereoMode::SideBySide,
        StereoMode::SideBySideFull,
        StereoMode::TopBottom,
        StereoMode::RowInterleaved,
        StereoMode::ColumnInterleaved,
        StereoMode::Checkerboard,
    ] {
        let (packed, _) = stereo_pack(&ctx, (&l, &r), mode, size).expect("packs");
        let (pw, ph) = mode.packed_size(size);
        assert_eq!(packed.len(), (pw * ph * 4) as usize, "{mode:?}");
        for y in 0..ph {
            for x in 0..pw {
                let (left, sx, sy) = spatial_source(mode, size, x, y);
                let want = texel(if left { &l } else { &r }, size.0, sx, sy);
                assert_eq!(texel(&packed, pw, x, y), want, "{mode:?} at ({x}, {y})");
            }
        }
    }
    common::assert_no_validation_messages(&ctx);
}

fn decode(c: u8) -> f64 {
    let c = c as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn encode(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    255.0
        * if c <= 0.0031308 {
            c * 12.92
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        }
}

type M3 = [[f64; 3]; 3];

/// The published anaglyph matrices (left, right), by rows, applied to linear RGB. True, gray,
/// color and half-color: the classic definitions with Rec. 601 luma (0.299, 0.587, 0.114), as
/// tabulated in Wimmer 2004, "Anaglyph methods comparison". Dubois: the red-cyan least-squares
/// matrices of E. Dubois's projection method (Dubois 2001, "A projection method to generate
/// anaglyph stereo images", ICASSP 2001), the numbers as published on his University of Ottawa
/// anaglyph page for red-cyan glasses.
fn published(mode: StereoMode) -> (M3, M3) {
    const Y: [f64; 3] = [0.299, 0.587, 0.114];
    const O: [f64; 3] = [0.0; 3];
    match mode {
        StereoMode::AnaglyphTrue => ([Y, O, O], [O, O, Y]),
        StereoMode::AnaglyphGray => ([Y, O, O], [O, Y, Y]),
        StereoMode::AnaglyphColor => (
            [[1.0, 0.0, 0.0], O, O],
            [O, [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        ),
        StereoMode::AnaglyphHalfColor => ([Y, O, O], [O, [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        StereoMode::AnaglyphDubois => (
            [
                [0.437, 0.449, 0.164],
                [-0.062, -0.062, -0.024],
                [-0.048, -0.050, -0.017],
            ],
            [
                [-0.011, -0.032, -0.007],
                [0.377, 0.761, 0.009],
                [-0.026, -0.093, 1.234],
            ],
        ),
        _ => unreachable!(),
    }
}

#[test]
fn anaglyphs_apply_the_published_matrices_in_linear_rgb() {
    let ctx = common::context();
    let size = (8, 6);
    let (l, r) = eyes(size.0, size.1);
    for mode in [
        StereoMode::AnaglyphTrue,
        StereoMode::AnaglyphGray,
        StereoMode::AnaglyphColor,
        StereoMode::AnaglyphHalfColor,
        StereoMode::AnaglyphDubois,
    ] {
        let (packed, _) = stereo_pack(&ctx, (&l, &r), mode, size).expect("packs");
        let (ml, mr) = published(mode);
        for y in 0..size.1 {
            for x in 0..size.0 {
                let (a, b) = (texel(&l, size.0, x, y), texel(&r, size.0, x, y));
                let got = texel(&packed, size.0, x, y);
                for c in 0..3 {
                    let lin: f64 = (0..3)
                        .map(|k| ml[c][k] * decode(a[k]) + mr[c][k] * decode(b[k]))
                        .sum();
                    let want = encode(lin);
                    // One 8-bit step: the GPU's f32 pow and its rounding vs f64 here.
                    assert!(
                        (got[c] as f64 - want).abs() <= 1.0,
                        "{mode:?} at ({x}, {y}) channel {c}: {} vs {want:.2}",
                        got[c]
                    );
                }
            }
        }
    }
    common::assert_no_validation_messages(&ctx);
}

//! Order-independent transparency (per-pixel linked lists, `--transparency oit`): layers of
//! known colour blended in every draw order against the closed form of the "over" operator,
//! more layers than K (the nearest K blended, the rest counted), a full node buffer (counted,
//! the image still defined), and no transparency passes where nothing is transparent. Each
//! render runs with validation and synchronization validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::render::{render_image, RenderOutput, RenderSettings, OIT_MAX_LAYERS};
use voxgi::scene::{Scene, Transparency};

const SIZE: u32 = 64;
/// Radiance of the opaque floor behind the layers (emissive, black albedo: no lights needed).
const BACKGROUND: Vec3 = Vec3::new(0.2, 0.3, 0.4);
/// Pixels around the image centre, where every layer of the scenes below is in view: a quad of
/// half-size 0.5 m at 1.0 m height is 2 m from the camera, tan = 0.25 against the half-field
/// tan 30° = 0.577, so it covers the central ±13.9 pixels.
const CENTRE: std::ops::Range<u32> = 24..40;

/// Looking straight down from 3 m at an emissive floor; `layers` are (height m, emitted
/// radiance, opacity) of unit quads (black albedo, so their colour is exactly the emission).
fn layered_scene(layers: &[(f32, Vec3, f32)]) -> Scene {
    let mut toml = format!(
        "[camera]\nposition = [0.0, 3.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n\
         fov_y_deg = 60.0\nnear = 0.05\nfar = 10.0\n\n\
         [[objects]]\nname = \"floor\"\nbuiltin = \"quad\"\nscale = [6.0, 1.0, 6.0]\n\
         material = {{ albedo = [0.0, 0.0, 0.0], emission_w_sr_m2 = [{}, {}, {}] }}\n",
        BACKGROUND.x, BACKGROUND.y, BACKGROUND.z
    );
    for (i, (height, c, alpha)) in layers.iter().enumerate() {
        toml += &format!(
            "\n[[objects]]\nname = \"layer{i}\"\nbuiltin = \"quad\"\ntranslate = [0.0, {height}, 0.0]\n\
             material = {{ albedo = [0.0, 0.0, 0.0], emission_w_sr_m2 = [{}, {}, {}], opacity = {alpha} }}\n",
            c.x, c.y, c.z
        );
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(&toml, Path::new("<oit test scene>"), &dir).expect("test scene parses")
}

fn render(scene: &Scene, transparency: Transparency, nodes_per_pixel: u32) -> RenderOutput {
    let ctx = common::context();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        transparency,
        oit_nodes_per_pixel: nodes_per_pixel,
        ..Default::default()
    };
    let out = render_image(&ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    assert!(
        out.hdr.data.iter().all(|p| p.iter().all(|c| c.is_finite())),
        "no NaN/Inf in the image"
    );
    out
}

fn pixel(out: &RenderOutput, x: u32, y: u32) -> Vec3 {
    Vec3::from(out.hdr.data[(y * SIZE + x) as usize])
}

/// The "over" operator applied back to front: `layers` nearest first, over `behind`.
fn blend_over(layers: &[(Vec3, f32)], behind: Vec3) -> Vec3 {
    layers
        .iter()
        .rev()
        .fold(behind, |c, &(colour, a)| a * colour + (1.0 - a) * c)
}

/// Bound of the blended colour's error. Each layer's radiance is stored as a half float in its
/// node, and the floor's emission passes through the RGBA16F G-buffer: each value is off by at
/// most 2⁻¹¹ of itself (10 explicit mantissa bits, round to nearest). The blend is a convex
/// combination (weights a(1 − a)^j and (1 − a)^n sum to 1, and a = 0.5, 0.25 are exact in half
/// floats), so its error is at most 2⁻¹¹ · max value; 1e-6 covers the f32 arithmetic.
fn bound(values: &[Vec3]) -> f32 {
    let max = values.iter().map(|v| v.max_element()).fold(0.0, f32::max);
    max * 2f32.powi(-11) + 1e-6
}

/// Pixels whose centre ray meets the unit quad at `height` (|x|, |z| < 0.5). No quad edge of
/// these scenes passes within a quarter pixel of a pixel centre, so rasterization agrees.
fn covered_pixels(scene: &Scene, height: f32) -> u32 {
    let mut n = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let (a, b) = common::pixel_ray_points(scene, x, y, SIZE);
            let p = a + (b - a) * ((a.y - height) / (a.y - b.y));
            n += u32::from(p.x.abs() < 0.5 && p.z.abs() < 0.5);
        }
    }
    n
}

#[test]
fn three_half_transparent_layers_blend_as_the_closed_form_in_every_draw_order() {
    let (a, heights) = (0.5, [1.4, 1.2, 1.0]);
    let colours = [
        Vec3::new(1.0, 0.1, 0.1),
        Vec3::new(0.1, 0.8, 0.2),
        Vec3::new(0.2, 0.3, 1.5),
    ];
    // C = a c1 + (1 − a)(a c2 + (1 − a)(a c3 + (1 − a) B)), c1 the nearest.
    let want = blend_over(&colours.map(|c| (c, a)), BACKGROUND);
    let mut values = colours.to_vec();
    values.push(BACKGROUND);
    let tolerance = bound(&values);
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    // The check can fail: blending the layers in any other depth order gives another colour.
    for wrong in &orders[1..] {
        let other = blend_over(&wrong.map(|i| (colours[i], a)), BACKGROUND);
        assert!(
            (other - want).abs().max_element() > 10.0 * tolerance,
            "{wrong:?}"
        );
    }
    for order in orders {
        let layers: Vec<_> = order.iter().map(|&i| (heights[i], colours[i], a)).collect();
        let out = render(&layered_scene(&layers), Transparency::Oit, 4);
        for y in CENTRE {
            for x in CENTRE {
                let got = pixel(&out, x, y);
                assert!(
                    (got - want).abs().max_element() <= tolerance,
                    "draw order {order:?}, pixel ({x}, {y}): {got}, expected {want} (± {tolerance})"
                );
            }
        }
        // Outside every layer: the floor alone.
        let corner = pixel(&out, 1, 1);
        assert!((corner - BACKGROUND).abs().max_element() <= bound(&[BACKGROUND]));
        let stats = out.oit.expect("the scene has transparency lists");
        assert_eq!(stats.fragments_dropped(), 0);
        assert_eq!(stats.pixels_over_max_layers, 0);
        assert_eq!(stats.overflow_warning(), None);
    }
}

#[test]
fn more_layers_than_k_blend_the_nearest_k_and_are_counted() {
    // 18 layers 5 cm apart, a = 0.25; the two lowest (farthest) are bright, so leaving them out
    // changes the centre by about 0.25 · 0.75^16 · 40 = 0.1, far above the bound.
    let a = 0.25;
    let n = OIT_MAX_LAYERS as usize + 2;
    let layers: Vec<(f32, Vec3, f32)> = (0..n)
        .map(|i| {
            let colour = if i < 2 {
                Vec3::new(40.0, 20.0, 10.0)
            } else {
                Vec3::new(0.05 * i as f32, 0.3, 1.0 - 0.04 * i as f32)
            };
            (1.0 + 0.05 * i as f32, colour, a)
        })
        .collect();
    let scene = layered_scene(&layers);
    let out = render(&scene, Transparency::Oit, 32);
    // Nearest first: the highest layers; the K nearest over the floor.
    let nearest: Vec<(Vec3, f32)> = layers.iter().rev().map(|&(_, c, a)| (c, a)).collect();
    let kept = &nearest[..OIT_MAX_LAYERS as usize];
    let want = blend_over(kept, BACKGROUND);
    let all = blend_over(&nearest, BACKGROUND);
    let mut values: Vec<Vec3> = kept.iter().map(|l| l.0).collect();
    values.push(BACKGROUND);
    let tolerance = bound(&values);
    assert!((all - want).abs().max_element() > 100.0 * tolerance);
    for y in CENTRE {
        for x in CENTRE {
            let got = pixel(&out, x, y);
            assert!(
                (got - want).abs().max_element() <= tolerance,
                "pixel ({x}, {y}): {got}, expected the nearest {OIT_MAX_LAYERS} layers {want} (± {tolerance}; all layers: {all})"
            );
        }
    }
    // The lowest layer has the smallest image and every other layer covers it: exactly its
    // pixels hold 18 layers and drop 2; every fragment fits the buffer (32 per pixel).
    let stats = out.oit.expect("the scene has transparency lists");
    let deepest = covered_pixels(&scene, layers[0].0);
    let fragments: u32 = layers.iter().map(|l| covered_pixels(&scene, l.0)).sum();
    assert!(deepest > 300, "{deepest} pixels see every layer");
    assert_eq!(stats.fragments, fragments);
    assert_eq!(stats.fragments_dropped(), 0);
    assert_eq!(stats.pixels_over_max_layers, deepest);
    assert_eq!(stats.layers_over_max_layers, 2 * deepest);
    assert!(stats.overflow_warning().is_some());
}

#[test]
fn a_full_node_buffer_drops_fragments_counts_them_and_stays_defined() {
    // 8 layers over about 900 pixels each need more than the 64² nodes of one per pixel.
    let layers: Vec<(f32, Vec3, f32)> = (0..8)
        .map(|i| {
            (
                1.0 + 0.1 * i as f32,
                Vec3::new(1.0, 0.5, 0.1 * i as f32),
                0.5,
            )
        })
        .collect();
    let scene = layered_scene(&layers);
    let out = render(&scene, Transparency::Oit, 1);
    let stats = out.oit.expect("the scene has transparency lists");
    let fragments: u32 = layers.iter().map(|l| covered_pixels(&scene, l.0)).sum();
    assert_eq!(stats.capacity, SIZE * SIZE);
    assert_eq!(stats.fragments, fragments);
    assert_eq!(stats.fragments_dropped(), fragments - SIZE * SIZE);
    assert!(stats
        .overflow_warning()
        .is_some_and(|w| w.contains("--oit-nodes-per-pixel")));
    // Whatever was kept, every pixel is a convex combination of the layers and the floor.
    let mut values: Vec<Vec3> = layers.iter().map(|l| l.1).collect();
    values.push(BACKGROUND);
    let (lo, hi) = values
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    let slack = bound(&values);
    for p in &out.hdr.data {
        let p = Vec3::from(*p);
        assert!(
            p.cmpge(lo - slack).all() && p.cmple(hi + slack).all(),
            "{p} outside [{lo}, {hi}]"
        );
    }
}

#[test]
fn only_scenes_with_transparency_in_oit_mode_get_the_transparency_passes() {
    let is_oit = |p: &String| p.starts_with("oit_");
    let half = [(1.0, Vec3::ONE, 0.5)];
    let opaque = [(1.0, Vec3::ONE, 1.0)];
    let with = render(&layered_scene(&half), Transparency::Oit, 4);
    assert!(with.live_passes.iter().any(|p| p == "oit_gather"));
    assert!(with.live_passes.iter().any(|p| p == "oit_resolve"));
    let cases = [
        (&opaque[..], Transparency::Oit, "an opaque scene"),
        (&half[..], Transparency::Hashed, "--transparency hashed"),
    ];
    for (layers, mode, what) in cases {
        let out = render(&layered_scene(layers), mode, 4);
        assert!(
            !out.live_passes.iter().any(is_oit),
            "{what}: {:?}",
            out.live_passes
        );
        assert_eq!(out.oit, None, "{what}");
    }
}

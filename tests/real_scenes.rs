//! The third-party scenes (`assets/realscenes/`, scene files in `assets/scenes/`) load and
//! render with every GI method at a tiny size, validation clean, and their images are lit
//! where a working loader must light them; and the path tracer keeps the energy of Mitsuba 3
//! rendering the same scenes (CornellBox-Original; Sponza under the sun, per bounce).
//! Measurements against the authors' references are in docs/measurements/real-scenes.md.

mod common;

use voxgi::gi::GiMethod;
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{resolve_gi, schema::Layer, Scene};

const WIDTH: u32 = 32;
const HEIGHT: u32 = 18;
const METHODS: [GiMethod; 5] = [
    GiMethod::None,
    GiMethod::Hemisphere,
    GiMethod::Pathtrace,
    GiMethod::Vpl,
    GiMethod::Ssgi,
];

fn load(file: &str) -> Scene {
    let path = format!("{}/assets/scenes/{file}", env!("CARGO_MANIFEST_DIR"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{path} loads: {e}"))
}

fn triangles(scene: &Scene) -> usize {
    scene.meshes.iter().map(|m| m.indices.len() / 3).sum()
}

/// Renders `scene` at 32x18 with `method` and the scene's other `[gi]` values, on one
/// validating context, and returns the number of pixels whose radiance sum exceeds 1e-3 (the
/// threshold of tests/atrium.rs: far below any lit surface here, far above a black one).
fn lit_pixels(ctx: &voxgi::vk::Context, scene: &Scene, method: GiMethod) -> usize {
    let mut gi = resolve_gi(&scene.gi, &Layer::default());
    gi.method = method;
    let settings = RenderSettings {
        width: WIDTH,
        height: HEIGHT,
        gi,
        ..Default::default()
    };
    let out = render_image(ctx, scene, &settings)
        .unwrap_or_else(|e| panic!("renders with {method:?}: {e}"));
    common::assert_no_validation_messages(ctx);
    assert!(
        out.hdr.data.iter().flatten().all(|c| c.is_finite()),
        "{method:?}: every pixel is finite"
    );
    out.hdr
        .data
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 1e-3)
        .count()
}

/// Renders with every method on one context and returns the lit-pixel count per method, in
/// the order of `METHODS`.
fn lit_per_method(scene: &Scene) -> Vec<usize> {
    let ctx = common::context();
    METHODS
        .iter()
        .map(|&m| lit_pixels(&ctx, scene, m))
        .collect()
}

const PIXELS: usize = (WIDTH * HEIGHT) as usize;

#[test]
fn cornell_original_lit_by_its_emissive_quad_through_gi() {
    let scene = load("cornell_original.toml");
    // 18 quads as published (5 walls, 6 faces of each box, the light), two triangles each.
    assert_eq!(
        triangles(&scene),
        36,
        "every quad of the OBJ, as two triangles"
    );
    let lit = lit_per_method(&scene);
    // No light but the emissive quad: without GI its direct light comes from
    // `direct_emitters` (light samples on the quad's triangles), with GI from the methods.
    // The open front (+-1 m at 2.41 m) spans +-0.41/0.36 of the half-height, i.e. every row,
    // and 1/2.41/0.65 = 64% of the width: the box's inside covers about 370 of 576 pixels,
    // all of it facing the light except the boxes' sides turned away from it. A GI method
    // that reads the emitter (or the direct light that samples it) lights at least the back
    // wall, 11 x 11 pixels (2 m at 4.44 m), and the side walls; require a quarter of the
    // image. A loader that loses the emitter, its `Ke` or the walls lights nothing.
    // (Measured: none 251, hemisphere 274, path tracer 323, VPLs 360.)
    // Screen-space GI gathers only what is on screen, and at 32x18 the quad covers no pixel
    // centre, so its image is black by design (it leaves the emitters' direct light to its
    // own gather, docs/design/emitter-sampling.md) and is checked for validation and finite
    // values only.
    for (method, &n) in METHODS.iter().zip(&lit) {
        if *method == GiMethod::Ssgi {
            continue;
        }
        assert!(
            n * 4 >= PIXELS,
            "{method:?}: only {n} of {PIXELS} pixels are lit"
        );
    }
}

#[test]
fn modern_hall_lit_by_its_emitters_through_gi() {
    let mut scene = load("modern_hall.toml");
    assert_eq!(
        scene.voxel_settings().max_res_xy,
        512,
        "the scene's [voxel] grid"
    );
    // This test guards loading, lighting and validation, not accuracy: the default grid, as
    // the scene's 512 columns x 4 layers cost five times the time (about 19 s a render here).
    scene.voxel = Layer::default();
    // Every one of the flattened OBJ's 31,087 `f` lines, each a triangle (its emitter disks
    // and rectangles included).
    assert_eq!(triangles(&scene), 31_087);
    // Its emitting materials (13 in the MTL, `Ke` 1.5 to 4.6) are the only light.
    let emitters = scene
        .materials
        .iter()
        .filter(|m| m.emission.max_element() > 0.0)
        .count();
    assert!(emitters > 0, "the MTL's `Ke` emitters are read");
    let lit = lit_per_method(&scene);
    // The view is walls, stairs and floor in a hall lit by 13 emitters (four large panels
    // outside its windows carry nearly all of the power); the authors' reference has no pixel whose radiance sum is below 0.03. Without
    // GI their direct light comes from `direct_emitters`, with GI from the methods. Require a
    // quarter of the image: a loader that loses the `Ke` values lights nothing. (Measured:
    // `none` 371 (24 before the emitters' direct light), hemisphere 493, path
    // tracer 536, VPLs 560, and screen-space GI 430, which gathers from the emitters in view,
    // the tall one at the left among them; before the loader rewound the two window emitters
    // wound against their normals, which only adds light.)
    for (method, &n) in METHODS.iter().zip(&lit) {
        assert!(
            n * 4 >= PIXELS,
            "{method:?}: only {n} of {PIXELS} pixels are lit"
        );
    }
}

#[test]
fn sponza_lit_by_the_sun_with_every_method() {
    let mut scene = load("sponza.toml");
    // Loading, lighting and validation at the default grid (the scene's 512 columns cost
    // several times the time; see the Modern Hall's test).
    scene.voxel = Layer::default();
    assert_eq!(triangles(&scene), 66_445);
    // sponza.mtl gives 17 of its 19 materials a JPEG `map_Kd`.
    let textured = scene
        .materials
        .iter()
        .filter(|m| m.albedo_texture.is_some())
        .count();
    assert_eq!(textured, 17, "every JPEG texture loads");
    let lit = lit_per_method(&scene);
    // The camera looks from the upper gallery down across the courtyard, whose floor and
    // facing arcades fill the lower half of the view; the sun reaches them through the roof
    // opening in direct light, which every method shows. Require an eighth of the image lit
    // by every method: a loader that loses the mesh or its light leaves it black.
    for (method, &n) in METHODS.iter().zip(&lit) {
        assert!(
            n * 8 >= PIXELS,
            "{method:?}: only {n} of {PIXELS} pixels are lit"
        );
    }
}

/// CornellBox-Original's energy: the path tracer, with the scene's `[gi]` (unbounded paths, as
/// the reference's `path` integrator with max depth 64), against Mitsuba 3 rendering the
/// authors' OBJ (assets/references/cornell_original_authors.exr, 256², 512 spp; its Lambert
/// materials and emissive quad are voxgi's own, so the mapping costs nothing here, relMSE
/// 2e-5 between the authors' and voxgi's export), box-filtered to 64².
///
/// The pixels of the light itself (radiance 17, 12, 4) are left out, in either image: at 64²
/// a pixel centre on the light's outline is the light in ours and a blend in the box-filtered
/// reference. Measured off the light: 1.006 here (4 rays × 4 frames), 1.009 at 256² (4 × 16).
/// Per bounce against Mitsuba at max depth 2 and 3: the direct light 0.985, the first indirect
/// bounce 1.036 (docs/measurements/real-scenes.md, "Energy per bounce"; before the light
/// samples took their geometry at the surface point, 1.008 and 1.063, and the whole 1.033).
/// The bound is issue #33's 3%: the measured 0.6% leaves 2.4% for another device's rounding
/// and the mean's noise (below 0.5% at 64² × 16 paths). With 2 bounces (the default) the path
/// tracer has 77% and fails: the bound tells a lost bounce.
#[test]
fn cornell_original_path_tracer_keeps_the_references_energy() {
    use voxgi::eval::HdrImage;
    let scene = load("cornell_original.toml");
    let reference = voxgi::bench::sweep::downsample(
        &HdrImage::load_exr(format!(
            "{}/assets/references/cornell_original_authors.exr",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("the reference"),
        4,
    );
    let mut gi = resolve_gi(&scene.gi, &Layer::default());
    (gi.method, gi.rays, gi.accumulate_frames) = (GiMethod::Pathtrace, 4, 4);
    let settings = RenderSettings {
        width: reference.width,
        height: reference.height,
        gi,
        ..Default::default()
    };
    let ctx = common::context();
    let img = render_image(&ctx, &scene, &settings).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    let (mut ours, mut theirs) = (0.0f64, 0.0f64);
    for (a, r) in img.data.iter().zip(&reference.data) {
        if r.iter().chain(a).all(|&c| c < 2.0) {
            ours += a.iter().map(|&c| f64::from(c)).sum::<f64>();
            theirs += r.iter().map(|&c| f64::from(c)).sum::<f64>();
        }
    }
    let ratio = ours / theirs;
    println!("cornell_original path tracer: {ratio:.4} of the reference's mean radiance");
    assert!(
        (ratio - 1.0).abs() < 0.03,
        "the path tracer has {ratio:.4} of the reference's energy"
    );
}

/// Renders `sponza.toml` with the `voxgi` binary (the scene's own `[shadow]`, `[voxel]` and
/// `[gi]` under `args`, validation on) at the references' 160x90 and returns the image.
fn render_sponza(dir: &std::path::Path, name: &str, args: &[&str]) -> voxgi::eval::HdrImage {
    let scene = format!("{}/assets/scenes/sponza.toml", env!("CARGO_MANIFEST_DIR"));
    let exr = dir.join(format!("{name}.exr"));
    let png = dir.join(format!("{name}.png"));
    let exr_arg = exr.to_str().expect("utf-8 temp path");
    let png_arg = png.to_str().expect("utf-8 temp path");
    let mut all = vec![
        "--validate",
        "render",
        &scene,
        "--width",
        "160",
        "--height",
        "90",
    ];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--exr", exr_arg, "-o", png_arg]);
    let out = common::voxgi(&all);
    assert!(
        out.status.success(),
        "voxgi {all:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    voxgi::eval::HdrImage::load_exr(&exr).expect("the render's EXR")
}

fn sum(img: &voxgi::eval::HdrImage) -> f64 {
    img.data.iter().flatten().map(|&c| f64::from(c)).sum()
}

/// Sponza under the sun, per bounce, against Mitsuba 3 rendering voxgi's export of the same
/// scene (the mapped render; `voxgi export-mitsuba assets/scenes/sponza.toml --width 160
/// --height 90`, then `tools/reference` at max depth 2, 256 spp: assets/references/
/// sponza_sun_d2.exr, the direct light; and at max depth 3, 512 spp: sponza_sun_d3.exr, the
/// direct light and one bounce). The path tracer with `gi.bounces = 1`, 8 rays x 4 frames,
/// less voxgi's direct light (`--gi none`) is its first bounce, compared with d3 - d2.
///
/// Measured: the direct light 1.008 of Mitsuba's, the first bounce 1.010 (1.004 at 16 rays
/// x 8 frames, so about 0.6% of noise). The first bounce measured 1.050 when the bounce
/// vertices took the sun's shadow maps at the ray's entry into the hit voxel (up to a voxel
/// in front of the surface) instead of on the owner triangle's plane, and the direct light
/// 1.025 with 1024-texel maps, whose PCF normal offset lights a band along every shadow edge
/// (docs/measurements/real-scenes.md, "Energy against the mapped renders"). The bound is
/// issue #33's 3% for the energy against the mapped render; the references' own noise is
/// below 0.1% of their mean (tools/reference's relMSE estimates, 3e-4 and 1e-3 per pixel,
/// over 14,400 pixels).
#[test]
fn sponza_sun_bounce_energy_matches_the_mapped_render() {
    use voxgi::eval::HdrImage;
    let refs = format!("{}/assets/references", env!("CARGO_MANIFEST_DIR"));
    let d2 = HdrImage::load_exr(format!("{refs}/sponza_sun_d2.exr")).expect("d2 reference");
    let d3 = HdrImage::load_exr(format!("{refs}/sponza_sun_d3.exr")).expect("d3 reference");
    let dir = common::temp_dir("sponza-bounce");
    let direct = render_sponza(&dir, "none", &["--gi", "none"]);
    let one = render_sponza(
        &dir,
        "b1",
        &[
            "--gi",
            "pathtrace",
            "--gi-rays",
            "8",
            "--gi-frames",
            "4",
            "--set",
            "gi.bounces=1",
        ],
    );
    assert_eq!((direct.width, direct.height), (d2.width, d2.height));
    let direct_ratio = sum(&direct) / sum(&d2);
    let bounce_ratio = (sum(&one) - sum(&direct)) / (sum(&d3) - sum(&d2));
    println!("sponza under the sun: direct {direct_ratio:.4}, first bounce {bounce_ratio:.4} of Mitsuba's");
    assert!(
        (direct_ratio - 1.0).abs() < 0.03,
        "the direct light has {direct_ratio:.4} of the mapped render's"
    );
    assert!(
        (bounce_ratio - 1.0).abs() < 0.03,
        "the first bounce has {bounce_ratio:.4} of the mapped render's"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

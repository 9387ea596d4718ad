//! The emissive triangles' and the environment's direct light (`direct_emitters`): where it
//! runs (only where no GI method brings that light, and only then with a voxel grid), a
//! closed form under a constant sky, and the emissive Cornell box and the sky-lit courtyard
//! under `--gi none` against Mitsuba 3's direct light. Validation on.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::gi::{GiMethod, GiSettings};
use voxgi::render::{render_image, RenderSettings, Renderer};
use voxgi::scene::{load_scene_arg, Scene};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn scene(arg: &str) -> Scene {
    load_scene_arg(Some(arg)).expect("loads")
}

fn cornell_emissive() -> Scene {
    scene(&format!("{ROOT}/assets/scenes/cornell_emissive.toml"))
}

/// A 4 m Lambert floor (albedo 0.5) at y = 0 under a constant sky of radiance `sky`, seen
/// from above (the lower rows show the floor, the upper the sky).
fn floor_under(sky: Vec3) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [0.0, 1.0, -1.5]
target = [0.0, 0.6, 0.0]
fov_y_deg = 60.0
[[objects]]
builtin = "quad"
scale = [4.0, 1.0, 4.0]
material = {{ albedo = 0.5 }}
[environment]
kind = "constant"
radiance = [{}, {}, {}]
"#,
        sky.x, sky.y, sky.z
    );
    Scene::from_toml_str(&toml, Path::new("<floor scene>"), Path::new(ROOT)).expect("parses")
}

fn settings(method: GiMethod, size: (u32, u32), samples: u32) -> RenderSettings {
    let mut s = RenderSettings {
        width: size.0,
        height: size.1,
        gi: GiSettings {
            method,
            rays: 4,
            ..Default::default()
        },
        ..Default::default()
    };
    s.shadow.direct_samples = samples;
    s
}

/// Whether the renderer of `scene` under `method` declares the pass, and whether it made a
/// voxel grid (a static object can move only in a renderer without one).
fn has_pass_and_grid(ctx: &common::TestContext, scene: &Scene, method: GiMethod) -> (bool, bool) {
    let r = Renderer::new(ctx, scene, settings(method, (32, 32), 1)).expect("renderer");
    let g = r.graph();
    let has = g.pass_names().any(|n| n == "direct_emitters");
    (has, !r.can_move(0))
}

/// Who brings the emitters' and the environment's light to a pixel's surface, counted once
/// (docs/design/emitter-sampling.md, "Who brings which light"), as the methods' specs state
/// it: the pass runs for the emitters under `none` and `ssgi` (which gathers only the
/// emitters the camera sees; the pass samples the others), for the environment under `none`,
/// `ssgi` and `vpl` (whose rays never read it); the methods that bring that light themselves
/// keep their own path, their frames have no such pass (so their renders are those of
/// before). A scene with neither emitters nor an environment gets no pass and, under
/// `--gi none`, no voxel grid.
#[test]
fn the_pass_runs_only_where_no_method_brings_the_light() {
    let ctx = common::context();
    let emissive = cornell_emissive();
    for m in [GiMethod::None, GiMethod::Ssgi] {
        assert_eq!(
            has_pass_and_grid(&ctx, &emissive, m),
            (true, true),
            "{m:?} on emitters"
        );
    }
    for m in [GiMethod::Hemisphere, GiMethod::Pathtrace, GiMethod::Vpl] {
        assert!(
            !has_pass_and_grid(&ctx, &emissive, m).0,
            "{m:?} on emitters"
        );
    }
    let plain = scene("cornell");
    assert_eq!(
        has_pass_and_grid(&ctx, &plain, GiMethod::None),
        (false, false)
    );
    let sky = floor_under(Vec3::ONE);
    for m in [GiMethod::None, GiMethod::Ssgi, GiMethod::Vpl] {
        assert_eq!(
            has_pass_and_grid(&ctx, &sky, m),
            (true, true),
            "{m:?} under a sky"
        );
    }
    for m in [GiMethod::Hemisphere, GiMethod::Pathtrace] {
        assert!(!has_pass_and_grid(&ctx, &sky, m).0, "{m:?} under a sky");
    }
    common::assert_no_validation_messages(&ctx);
}

/// A Lambert floor (albedo ρ) under a constant sky of radiance L with nothing above it, direct
/// light only: E = ∫ L cos θ dω = π L over the upper hemisphere, so L_o = ρ/π · π L = ρ L.
/// Every cosine-sampled direction leaves the grid unblocked and brings exactly L with weight 1
/// (f cos / pdf = ρ): the estimate has no variance, and the bound is float rounding (1e-3).
/// Without the pass (before this change) the floor was black under `--gi none`. The same
/// under `--gi vpl`: the scene has no lights, so no VPLs and no indirect light, and the
/// frame is the direct image.
#[test]
fn floor_under_a_constant_sky_reflects_rho_times_l_without_gi() {
    let ctx = common::context();
    let sky = Vec3::new(0.8, 1.0, 1.2);
    for method in [GiMethod::None, GiMethod::Vpl] {
        let img = render_image(&ctx, &floor_under(sky), &settings(method, (32, 32), 4))
            .expect("renders")
            .hdr;
        let floor = Vec3::from(img.data[(30 * img.width + 16) as usize]);
        let expected = 0.5 * sky;
        println!("{method:?}: floor {floor}, expected {expected}");
        assert!(
            (floor - expected).abs().max_element() < 1e-3 * expected.max_element(),
            "{method:?}: floor {floor}, expected ρL = {expected}"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// A 4 m Lambert floor (albedo 0.5) at y = 0 and a 1 m emissive square (radiance 4, its lit
/// side down) 1.5 m above it at z = `emitter_z`, no lights, seen from (0, 1, −1.5) looking
/// ahead and down: at z = −2.5 the emitter is behind the camera, at z = 1 in front of it and
/// its lit side in view.
fn floor_and_emitter(emitter_z: f32) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [0.0, 1.0, -1.5]
target = [0.0, 0.6, 0.0]
fov_y_deg = 60.0
[[objects]]
builtin = "quad"
scale = [4.0, 1.0, 4.0]
material = {{ albedo = 0.5 }}
[[objects]]
builtin = "quad"
translate = [0.0, 1.5, {emitter_z}]
rotate_deg = [180.0, 0.0, 0.0]
material = {{ albedo = 0.0, emission_w_sr_m2 = 4.0 }}
"#
    );
    Scene::from_toml_str(&toml, Path::new("<floor and emitter>"), Path::new(ROOT)).expect("parses")
}

/// The mean radiance of the floor's pixels (the lower third of the image, which sees the
/// floor only).
fn floor_mean(img: &HdrImage) -> f64 {
    let keep: Vec<bool> = (0..img.data.len() as u32)
        .map(|i| i / img.width >= 2 * img.height / 3)
        .collect();
    masked_mean(img, &keep)
}

/// Screen-space GI sees an emitter only where the camera does; `direct_emitters` brings the
/// light of the emitting points it does not see, and only those (its samples skip the points
/// the G-buffer shows on their lit side).
///
/// Behind the camera, the emitter lights the floor under `--gi ssgi` exactly as under
/// `--gi none`: the pass samples all of it with the same samples, and the gather adds nothing
/// (the only thing on screen is the flat floor, whose points see each other at cos θ = 0).
/// Before the method's spec said which emitters it brings, the floor was black under ssgi.
/// Measured ratio ssgi / none over the floor: 1.000 (bound 1%, for the gather's rounding of
/// coplanar positions).
///
/// In front of the camera with its lit side in view, the gather brings its light and the pass
/// skips every sample on it: the floor's light is the gather's alone, which the screen-space
/// patch areas (Oetke 2017 §5.2) approximate. Counted twice, the ratio would be near 2.
/// Measured: 0.917 (48², K = 8). Bound: within 35% of 1 (counted twice: near 2).
#[test]
fn ssgi_gets_the_light_of_the_emitters_it_cannot_see() {
    let ctx = common::context();
    for (z, bound) in [(-2.5f32, 0.01f64), (1.0, 0.35)] {
        let scene = floor_and_emitter(z);
        let mean = |method| {
            let img = render_image(&ctx, &scene, &settings(method, (48, 48), 8))
                .expect("renders")
                .hdr;
            floor_mean(&img)
        };
        let (none, ssgi) = (mean(GiMethod::None), mean(GiMethod::Ssgi));
        let ratio = ssgi / none;
        println!("emitter at z = {z}: floor none {none:.4}, ssgi {ssgi:.4}, ratio {ratio:.4}");
        assert!(none > 0.01, "the emitter lights the floor: {none}");
        assert!(
            (ratio - 1.0).abs() < bound,
            "emitter at z = {z}: ratio {ratio:.4}"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// The mean of 2 × 2 blocks: a 2w × 2h image at w × h (each pixel of a box-filtered
/// reference is the mean radiance over its area).
fn box_half(img: &HdrImage) -> HdrImage {
    let (w, h) = (img.width / 2, img.height / 2);
    let px = |x: u32, y: u32| Vec3::from(img.data[(y * img.width + x) as usize]);
    let data = (0..w * h)
        .map(|i| {
            let (x, y) = (2 * (i % w), 2 * (i / w));
            ((px(x, y) + px(x + 1, y) + px(x, y + 1) + px(x + 1, y + 1)) * 0.25).to_array()
        })
        .collect();
    HdrImage::new(w, h, data).expect("sizes agree")
}

/// The mean of the channels over the pixels where `keep` holds.
fn masked_mean(img: &HdrImage, keep: &[bool]) -> f64 {
    let (sum, n) = img
        .data
        .iter()
        .zip(keep)
        .filter(|(_, &k)| k)
        .fold((0.0f64, 0usize), |(s, n), (p, _)| {
            (s + p.iter().map(|&c| f64::from(c)).sum::<f64>(), n + 1)
        });
    sum / n.max(1) as f64
}

/// The emissive Cornell box under `--gi none` (the patch seen by the camera plus its light
/// reflected once, sampled by `direct_emitters`) against Mitsuba 3's direct light
/// (assets/references/cornell_emissive_direct.exr: max_depth 2, 1024 spp, 256², here
/// box-filtered to 128²).
///
/// Measured at 128², K = 32: mean ratio 0.978 away from the patch, relMSE 0.0086 (1.009 and
/// 0.0090 while the light samples took their geometry at the offset origin, which put every
/// surface δ nearer the patch). What is
/// noise and what is bias: at 256² against the unfiltered reference, relMSE is 0.00501 at
/// K = 32 and 0.00492 at K = 128; with relMSE(K) = b + n/K that is n = 0.004 and b = 0.0049,
/// so the noise at K = 32 is 1e-4 and nearly all of the error is bias: the voxel visibility
/// (shadow edges rounded to the grid, the segment stopping k₁ voxel diagonals off the patch),
/// the pixel centre against the reference's box filter at the patch's and the sphere's
/// outlines (which is why 128² reads higher than 256²), and the reference's own noise (its
/// 1024 spp). The mean over ~16000 pixels of K = 32 samples has a noise far below 0.1%.
/// Bounds: the mean within 3% (the measured 2.2%, with room for another device's rounding of
/// the same visibility decisions) and relMSE below 0.015 (the measured 0.009 × 1.5 + noise).
/// Wrong radiometry fails them by far: a missing cosine, 1/π or p_A moves the mean by tens of
/// percent, and the direct light alone is the whole of the image away from the patch.
#[test]
fn cornell_emissive_direct_light_matches_mitsuba() {
    let ctx = common::context();
    let reference = box_half(
        &HdrImage::load(Path::new(ROOT).join("assets/references/cornell_emissive_direct.exr"))
            .expect("reference"),
    );
    let img = render_image(
        &ctx,
        &cornell_emissive(),
        &settings(
            GiMethod::None,
            (reference.width, reference.height),
            EMISSIVE_SAMPLES,
        ),
    )
    .expect("renders")
    .hdr;
    common::assert_no_validation_messages(&ctx);
    // Away from the patch's own pixels (radiance 30; its rasterized outline would dominate).
    let keep: Vec<bool> = reference
        .data
        .iter()
        .map(|p| p.iter().all(|&c| c < 2.0))
        .collect();
    let ratio = masked_mean(&img, &keep) / masked_mean(&reference, &keep);
    let m = compare(&reference, &img, None).expect("same size");
    println!(
        "cornell_emissive --gi none: mean ratio {ratio:.4}, relMSE {:.4}",
        m.rel_mse
    );
    let (max_mean_error, max_rel_mse) = BOUNDS_EMISSIVE;
    assert!(
        (ratio - 1.0).abs() < max_mean_error,
        "mean off the pixels of the patch: {ratio:.4} of Mitsuba's"
    );
    assert!(m.rel_mse < max_rel_mse, "relMSE {:.4}", m.rel_mse);
}

/// K light samples per pixel of the emissive box's test.
const EMISSIVE_SAMPLES: u32 = 32;
/// (|mean ratio − 1|, relMSE) bounds of `cornell_emissive_direct_light_matches_mitsuba`.
const BOUNDS_EMISSIVE: (f64, f64) = (0.03, 0.015);

/// The sky-lit courtyard (no lights, an equirectangular sky) under `--gi none` against
/// Mitsuba 3's direct light (assets/references/sky_courtyard_direct.exr, max_depth 2, 1024
/// spp, 128²: the sky seen by the camera plus its light reflected once).
///
/// Measured at K = 32: mean ratio 0.993, relMSE 0.0101 since the map has a sampler without
/// anisotropy (docs/design/environment.md; before: mean ratio 0.990, relMSE 0.0153, and the
/// fit below, made then); at K = 128 relMSE 0.0138. With
/// relMSE(K) = b + n/K: n = 0.064 and b = 0.0133, so the noise at K = 32 is 0.002 and the rest
/// is bias: the voxel visibility (the walls' and blocks' outlines rounded to the grid decide
/// which directions near the horizon see the sky), the pixel centre against the box-filtered
/// reference at the bright sky's edges, and the reference's own noise (4e-4). Bounds: the mean
/// within 3% (the measured 1.0%, with room for another device's rounding) and relMSE below
/// 0.025 (the measured 0.0153 × 1.5 + the noise's spread). Without the pass the surfaces are
/// black and the mean is 45% of the reference's (the sky's own pixels): the surfaces make the
/// other 55%, so an error of 6% in their light (let alone a missing π or cosine) fails it.
#[test]
fn sky_courtyard_direct_light_matches_mitsuba() {
    let ctx = common::context();
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/sky_courtyard_direct.exr"))
            .expect("reference");
    let img = render_image(
        &ctx,
        &scene(&format!("{ROOT}/assets/scenes/sky_courtyard.toml")),
        &settings(
            GiMethod::None,
            (reference.width, reference.height),
            SKY_SAMPLES,
        ),
    )
    .expect("renders")
    .hdr;
    common::assert_no_validation_messages(&ctx);
    let all = vec![true; img.data.len()];
    let ratio = masked_mean(&img, &all) / masked_mean(&reference, &all);
    let m = compare(&reference, &img, None).expect("same size");
    println!(
        "sky_courtyard --gi none: mean ratio {ratio:.4}, relMSE {:.4}",
        m.rel_mse
    );
    let (max_mean_error, max_rel_mse) = BOUNDS_SKY;
    assert!(
        (ratio - 1.0).abs() < max_mean_error,
        "mean {ratio:.4} of Mitsuba's"
    );
    assert!(m.rel_mse < max_rel_mse, "relMSE {:.4}", m.rel_mse);
}

/// Environment directions per pixel of the courtyard's test.
const SKY_SAMPLES: u32 = 32;
/// (|mean ratio − 1|, relMSE) bounds of `sky_courtyard_direct_light_matches_mitsuba`.
const BOUNDS_SKY: (f64, f64) = (0.03, 0.025);

/// Under TAA (its 16 frames, the accumulator of the direct image) the samples advance by the
/// R2 sequence of the frame, so the frames average different samples: the sky-lit courtyard
/// at K = 4 against the same Mitsuba reference as above. Measured relMSE 0.0070 (0.0107 before the map's sampler lost its anisotropy; fixed
/// samples, before: 0.0509; one frame at K = 4: 0.0578, the same before and after, since a
/// frame that does not accumulate keeps its samples). The bias b of the K sweep above is
/// 0.0133 at the pixel centre; TAA's sub-pixel jitter box-filters the pixel as the reference
/// does, which is why the measurement is below it. Bound: 0.02 (the measured × 1.5, plus
/// room for another device's rounding), which the fixed samples fail by 2.5×.
#[test]
fn taa_averages_the_advancing_samples() {
    let ctx = common::context();
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/sky_courtyard_direct.exr"))
            .expect("reference");
    let mut s = settings(GiMethod::None, (reference.width, reference.height), 4);
    s.post.taa = Some(Default::default());
    let img = render_image(
        &ctx,
        &scene(&format!("{ROOT}/assets/scenes/sky_courtyard.toml")),
        &s,
    )
    .expect("renders")
    .hdr;
    common::assert_no_validation_messages(&ctx);
    let m = compare(&reference, &img, None).expect("same size");
    println!(
        "sky_courtyard --gi none --taa, K = 4: relMSE {:.4}",
        m.rel_mse
    );
    assert!(m.rel_mse < 0.02, "relMSE {:.4}", m.rel_mse);
}

/// Glossy receivers combine the light samples with samples of their specular lobe
/// (`emitter_lobe_hit`, multiple importance sampling). `cornell_pbr`'s tall block is a GGX
/// metal whose roughness map goes down to near-mirror: light samples alone (the pass before)
/// found its reflection of the emitting panel only in rare fireflies, so at K = 8 the block's
/// mean was 8% low (0.2188 against Mitsuba's 0.2394 at 128², and 0.2195 at K = 64: most
/// draws miss the rare large values) and pixels reached 2000 in a 0-to-3 image. With the lobe
/// samples it measures 0.2408 at K = 8 and 0.2401 at K = 64 (+0.6%), and the brightest block
/// pixel is the reference's own (6.0, the panel's mirror image). The reference is Mitsuba 3's direct light of voxgi's export (256 spp, its
/// own relMSE about 2e-3, so its block mean is good to far below 1%). Bounds: the block's mean
/// within 3% (the measured 0.6% plus the voxel visibility's rounding on another device; the
/// light samples alone fail it at -8%) and no block pixel above 10× the reference's brightest
/// there (fireflies).
#[test]
fn glossy_receivers_see_the_emitters_by_their_lobe_too() {
    let ctx = common::context();
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/cornell_pbr_direct.exr"))
            .expect("reference");
    let img = render_image(
        &ctx,
        &scene(&format!("{ROOT}/assets/scenes/cornell_pbr.toml")),
        &settings(GiMethod::None, (reference.width, reference.height), 8),
    )
    .expect("renders")
    .hdr;
    common::assert_no_validation_messages(&ctx);
    // The tall block's front at 128²: rows 45..105, columns 35..68.
    let w = reference.width as usize;
    let keep: Vec<bool> = (0..reference.data.len())
        .map(|i| (45..105).contains(&(i / w)) && (35..68).contains(&(i % w)))
        .collect();
    let ratio = masked_mean(&img, &keep) / masked_mean(&reference, &keep);
    let peak = |im: &HdrImage| {
        im.data
            .iter()
            .zip(&keep)
            .filter(|(_, &k)| k)
            .flat_map(|(p, _)| p.iter().copied())
            .fold(0.0f32, f32::max)
    };
    let (p_img, p_ref) = (peak(&img), peak(&reference));
    println!("cornell_pbr --gi none, the tall block: mean ratio {ratio:.4}, peak {p_img:.2} (reference {p_ref:.2})");
    assert!((ratio - 1.0).abs() <= 0.03, "block mean ratio {ratio}");
    assert!(p_img <= 10.0 * p_ref, "block peak {p_img} against {p_ref}");
}

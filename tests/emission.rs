//! Emissive surfaces as senders of indirect light (the emission volume): a Lambert floor under a
//! large emissive rectangle against the closed-form irradiance, and the emissive Cornell box
//! (no lights at all) against its Mitsuba full-GI reference. Validation on.

mod common;

use glam::Vec3;
use std::f32::consts::PI;
use std::path::Path;
use voxgi::eval::{compare, HdrImage};
use voxgi::gi::{Bounces, GiMethod, GiSettings, RadianceSource};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{load_scene_arg, Scene};
use voxgi::voxel::gpu::VoxelSettings;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Point-to-rectangle form factor from a differential area to a parallel a x b rectangle
/// centered on its normal at distance d (Howell, "A Catalog of Radiation Heat Transfer
/// Configuration Factors", factor B-3: the corner form
/// F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/c, Y = b/c; the
/// centered rectangle is four a/2 x b/2 ones sharing the corner above the point, so
/// F = 2/π [...] with X = a/(2d), Y = b/(2d)). An infinite rectangle gives 1.
fn form_factor(a: f32, b: f32, d: f32) -> f32 {
    let (x, y) = (a / (2.0 * d), b / (2.0 * d));
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / PI * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

/// Emitter side a = b (m), height d (m), radiance (W/(m² sr)) and the floor's albedo.
const SIDE_M: f32 = 1.0;
const HEIGHT_M: f32 = 0.5;
const EMISSION_W_SR_M2: f32 = 2.0;
const FLOOR_ALBEDO: f32 = 0.5;

/// A 2 m floor at y = 0 and, at height d above its center, the emitter turned over so that it
/// emits downward; no lights. The camera stays below the emitter and looks at the floor's
/// center, which therefore fills the central pixels.
fn emitter_scene(floor_material: &str) -> Scene {
    emitter_scene_with(
        floor_material,
        &format!("{{ albedo = 0.0, emission_w_sr_m2 = {EMISSION_W_SR_M2} }}"),
    )
}

/// [`emitter_scene`] with the emitter's material given (its emission must be
/// `EMISSION_W_SR_M2`).
fn emitter_scene_with(floor_material: &str, emitter_material: &str) -> Scene {
    let toml = format!(
        r#"
[camera]
position = [0.0, 0.45, -0.6]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
near = 0.01
far = 10.0
[[objects]]
builtin = "quad"
scale = [2.0, 1.0, 2.0]
material = {floor_material}
[[objects]]
builtin = "quad"
translate = [0.0, {HEIGHT_M}, 0.0]
rotate_deg = [180.0, 0.0, 0.0]
scale = [{SIDE_M}, 1.0, {SIDE_M}]
material = {emitter_material}
"#
    );
    Scene::from_toml_str(&toml, Path::new("<emitter scene>"), Path::new(ROOT)).expect("parses")
}

const SIZE: u32 = 64;
/// Half-width of the central window read (8 x 8 pixels).
const WINDOW: u32 = 4;

/// The floor's outgoing radiance under the emitter: direct light is zero (no lights, the floor
/// does not emit), so it is all the GI method's one bounce: ρ/π E with E = π L F, i.e.
/// ρ L F at a point on the emitter's axis (Lambert emitter of constant radiance L). The path
/// tracer and the hemisphere method (light maps, which see no emitters, plus the emission
/// volume at the hits) estimate it the same way.
///
/// The voxels make the rays see a slightly larger, nearer emitter: the voxels the
/// rectangle touches (exact conservative test) reach at most one voxel h beyond each edge and
/// their lower faces at most h below it, and rays start k1 √3 h above the floor (the normal
/// offset, k1 = 1). So the expected result lies between F(a, a, d) (the exact emitter) and
/// F(a + 2h, a + 2h, d − h − √3 h). The 8 x 8 central pixels see floor points up to about
/// 4 cm from the axis, where F is within 0.3% of its value on the axis (its maximum, with zero
/// slope). Noise: each sample returns L or 0 (probability F), so the window's estimate has a
/// relative sigma of at most √((1 − F)/(F n)) with n = 64 pixels x 8192 / 64 samples = 8192
/// independent-looking samples (path tracer: 32 rays x 4 frames; hemisphere: 128 rays in its
/// one frame): 1.0% (stratified samples do better); the bound adds 4% (4σ) on each side.
/// The VPLs' own estimate is described where they are configured.
#[test]
fn floor_under_an_emissive_rectangle_matches_the_form_factor() {
    let scene = emitter_scene(&format!("{{ albedo = {FLOOR_ALBEDO} }}"));
    let h = voxel_side_m(&scene);
    let ctx = common::context();
    let methods = [
        GiSettings {
            method: GiMethod::Pathtrace,
            rays: 32,
            bounces: Bounces::Fixed(1),
            accumulate_frames: 4,
            ..Default::default()
        },
        GiSettings {
            method: GiMethod::Hemisphere,
            rays: 128,
            ..Default::default()
        },
        // VPLs on the emitter itself (power-sampled source VPLs of gi_vpl_emit): 16 sets x 256,
        // all 16 sets within the window, so 4096 points on the exact emitter. Their estimator
        // cos_e cos_p / d² ranges over [0.44, 4] around its mean π F / A = 1.74, a relative
        // sigma of at most 0.6 per point, 0.6 / √4096 = 0.9% over the window (Halton points
        // do better); d_min = (1 voxel diagonal)² = 0.0008 m² against d² >= 0.25 m² lowers it
        // by at most 0.3%. The emitter is exact, so the voxel bound above is only wider.
        GiSettings {
            method: GiMethod::Vpl,
            vpl: voxgi::gi::vpl::VplSettings {
                per_set: 256,
                bounces: 1,
                d_min_voxels: 1.0,
                ..Default::default()
            },
            ..Default::default()
        },
    ];
    let (exact, largest) = floor_radiance_bounds(h);
    for gi in methods {
        let traced = central_floor_radiance(&ctx, &scene, gi);
        println!(
            "{:?}: voxel {h:.4} m: traced {traced:.4}, exact emitter {exact:.4}, voxel bound \
             {largest:.4} (F = {:.4})",
            gi.method,
            form_factor(SIDE_M, SIDE_M, HEIGHT_M)
        );
        assert!(
            traced > 0.96 * exact && traced < 1.04 * largest,
            "{:?}: floor radiance {traced} outside [{}, {}]",
            gi.method,
            0.96 * exact,
            1.04 * largest
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// The largest side of a voxel of `scene`'s default grid (m).
fn voxel_side_m(scene: &Scene) -> f32 {
    VoxelSettings::default()
        .grid_for(scene, 0.0)
        .expect("grid")
        .voxel_size_m()
        .max_element()
}

/// The floor's radiance ρ L F under the exact emitter, and under the largest emitter its
/// voxels of side `h` can stand for (derived above
/// `floor_under_an_emissive_rectangle_matches_the_form_factor`).
fn floor_radiance_bounds(h: f32) -> (f32, f32) {
    let (a, d) = (SIDE_M, HEIGHT_M);
    let expect = |f: f32| FLOOR_ALBEDO * EMISSION_W_SR_M2 * f;
    (
        expect(form_factor(a, a, d)),
        expect(form_factor(
            a + 2.0 * h,
            a + 2.0 * h,
            d - h - 3f32.sqrt() * h,
        )),
    )
}

/// The mean red radiance of the central 2·WINDOW x 2·WINDOW pixels of `scene` rendered with `gi`.
fn central_floor_radiance(ctx: &common::TestContext, scene: &Scene, gi: GiSettings) -> f32 {
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        gi,
        ..Default::default()
    };
    let img = render_image(ctx, scene, &settings).expect("renders").hdr;
    let mut sum = Vec3::ZERO;
    for y in SIZE / 2 - WINDOW..SIZE / 2 + WINDOW {
        for x in SIZE / 2 - WINDOW..SIZE / 2 + WINDOW {
            sum += Vec3::from(img.data[(y * SIZE + x) as usize]);
        }
    }
    sum.x / (4 * WINDOW * WINDOW) as f32
}

/// The form factor's limits: an infinite plane covers the hemisphere (F = 1), and a small
/// rectangle of area A at distance d gives A / (π d²) (a small Lambert source on the axis).
#[test]
fn form_factor_limits() {
    assert!((form_factor(1e4, 1e4, 1.0) - 1.0).abs() < 1e-3);
    let (a, d) = (0.01f32, 1.0f32);
    let small = a * a / (PI * d * d);
    assert!((form_factor(a, a, d) / small - 1.0).abs() < 1e-3);
}

/// A glossy emitter sends its emission, not its emission times the share its lobe leaves to
/// diffuse light: with no lights, a metal (GGX, metallic 1, base colour 0.9) emitter of
/// radiance L is, to a one-bounce method, the same Lambert source of radiance L as the black
/// emitter above (its reflected light is zero), so the floor reads the same ρ L F, within the
/// bounds of `floor_under_an_emissive_rectangle_matches_the_form_factor` (same emitter, grid
/// and rays). Those bounds are loose; the sharp check is against the light-map path, which
/// reads the emitter's radiance from the emission volume alone, casting the same rays: the
/// radiance volume stores emission beside the diffuse part of reflected light and scales
/// only the latter by the diffuse weight 1 − F(n·wo) (Schlick, F0 = 0.04) at a GGX hit;
/// applied to the emission as well it would send at most (1 − 0.04) L, 4% less (measured with
/// that change: 0.564 against 0.588), so the two paths must agree within 1%.
#[test]
fn a_metal_emitter_sends_its_emission_through_the_radiance_volume() {
    let scene = emitter_scene_with(
        &format!("{{ albedo = {FLOOR_ALBEDO} }}"),
        &format!(
            "{{ albedo = 0.9, metallic = 1.0, roughness = 0.5, emission_w_sr_m2 = {EMISSION_W_SR_M2} }}"
        ),
    );
    let h = voxel_side_m(&scene);
    let ctx = common::context();
    let (exact, largest) = floor_radiance_bounds(h);
    let [volume, maps] = [RadianceSource::Volume, RadianceSource::Maps].map(|radiance_source| {
        let gi = GiSettings {
            method: GiMethod::Hemisphere,
            rays: 128,
            radiance_source,
            ..Default::default()
        };
        let traced = central_floor_radiance(&ctx, &scene, gi);
        println!("{radiance_source:?}: traced {traced:.4}, exact {exact:.4}, bound {largest:.4}");
        assert!(
            traced > 0.96 * exact && traced < 1.04 * largest,
            "{radiance_source:?}: floor radiance {traced} outside [{}, {}]",
            0.96 * exact,
            1.04 * largest
        );
        traced
    });
    assert!(
        (volume / maps - 1.0).abs() < 0.01,
        "the radiance volume sends {volume}, the light-map path {maps}: the metal emitter's \
         emission is weighted like reflected light"
    );
    common::assert_no_validation_messages(&ctx);
}

/// The emissive Cornell box and its Mitsuba full-GI reference (256²).
fn emissive_box_and_reference() -> (voxgi::scene::Scene, HdrImage) {
    let scene = load_scene_arg(Some(&format!("{ROOT}/assets/scenes/cornell_emissive.toml")))
        .expect("loads");
    let reference =
        HdrImage::load(Path::new(ROOT).join("assets/references/cornell_emissive_gi.exr"))
            .expect("reference");
    (scene, reference)
}

/// The emissive Cornell box has no lights: everything but the patch itself is indirect light
/// from the patch, which the path tracer reads from the emission volume. Against the Mitsuba
/// full-GI reference (assets/references/cornell_emissive_gi.exr), 256², 2 bounces, 16 rays, one
/// frame: measured relMSE 0.056 without emitter sampling, 0.032 with it (the default; 0.067
/// with the copper sphere's lobe not sampled, i.e. black); the bound is the former plus 30%
/// for other devices' rounding and sample noise. Direct light only (`--gi none`, the patch
/// and its light reflected once by `direct_emitters`): 0.152 (0.488 when it showed
/// the patch alone); the path tracer's second bounce must bring it below half of that.
#[test]
fn emissive_cornell_box_is_lit_by_the_path_tracer() {
    let (scene, reference) = emissive_box_and_reference();
    let ctx = common::context();
    let mut rel_mse = Vec::new();
    for method in [GiMethod::None, GiMethod::Pathtrace] {
        let settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                method,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        rel_mse.push(
            compare(&reference, &out.hdr, None)
                .expect("same size")
                .rel_mse,
        );
    }
    common::assert_no_validation_messages(&ctx);
    println!(
        "emissive box relMSE: direct only {:.4}, path tracer {:.4}",
        rel_mse[0], rel_mse[1]
    );
    assert!(rel_mse[1] < 0.073, "path tracer relMSE {}", rel_mse[1]);
    assert!(rel_mse[1] < rel_mse[0] / 2.0, "path tracer {rel_mse:?}");
}

/// The radiance volume's second bounce in the emissive Cornell box: the volume pass samples
/// the emitter list at every voxel (next-event estimation, `gi_radiance_volume.comp`), so a
/// hemisphere ray that hits a wall brings the patch's light reflected there; without it
/// (`gi.emitter_sampling = false`) the volume holds only the patch's own emission and the
/// image has one bounce. Against the Mitsuba full-GI reference, 256², defaults (16 rays):
/// measured relMSE 0.0458 with the emitters (the path tracer's 0.032 above), 0.151 without.
/// Bounds: with, the measured value plus 30% for other devices' rounding and sample noise
/// (as above); and below half of the one-bounce image's, which a volume that missed the
/// emitters' light (or counted the patch's emission twice) would not reach.
#[test]
fn radiance_volume_brings_the_emitters_second_bounce() {
    let (scene, reference) = emissive_box_and_reference();
    let ctx = common::context();
    let [with, without] = [true, false].map(|emitter_sampling| {
        let settings = RenderSettings {
            width: 256,
            height: 256,
            gi: GiSettings {
                method: GiMethod::Hemisphere,
                radiance_source: RadianceSource::Volume,
                emitter_sampling,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders");
        compare(&reference, &out.hdr, None)
            .expect("same size")
            .rel_mse
    });
    common::assert_no_validation_messages(&ctx);
    println!("radiance volume relMSE: with the emitters {with:.4}, without {without:.4}");
    assert!(with < 0.06, "with the emitters: relMSE {with}");
    assert!(with < without / 2.0, "with {with}, without {without}");
}

/// Why `--gi hemisphere` and `--gi pathtrace` once gave the same image bit for bit in an
/// emission-only scene (#32): with no lights and Lambertian surfaces, the hemisphere method's
/// gather and the path tracer's first bounce are one estimator. Both trace the same
/// cosine-weighted voxel rays from the G-buffer point (the same per-pixel sample sequence) and
/// read the emission volume at the first hit (Thiedemann 2010, §6.3.3), and the light maps
/// they would otherwise read hold nothing. So the path tracer with one bounce and BSDF rays
/// only must equal the hemisphere image exactly; a difference means the two have drifted
/// apart. (A GGX surface breaks the identity on purpose: the path tracer samples the lobe, the
/// hemisphere method gathers cosine-weighted; in `cornell_emissive.toml` the copper sphere's
/// pixels differ.) The path tracer's defaults differ from the hemisphere method too: emitter
/// sampling (next-event estimation with MIS) changes the samples, and its second bounce adds
/// the light the lit walls send on, so it must be brighter.
#[test]
fn the_path_tracers_first_bounce_is_the_hemisphere_gather_in_an_emission_only_scene() {
    // The emissive Cornell box (`cornell_emissive.toml`) with its copper sphere left out: walls
    // of albedo ≤ 0.73, a white cube and the emitting patch, no lights.
    let toml = r#"
[camera]
position = [0.278, 0.273, -0.800]
target = [0.278, 0.273, 0.0]
fov_y_deg = 39.3
near = 0.01
far = 10.0
[[objects]]
builtin = "cornell_walls"
[[objects]]
builtin = "quad"
translate = [0.278, 0.5478, 0.2795]
rotate_deg = [180.0, 0.0, 0.0]
scale = [0.130, 1.0, 0.105]
material = { albedo = 0.0, emission_w_sr_m2 = [30.0, 30.0, 30.0] }
[[objects]]
builtin = "cube"
translate = [0.185, 0.0825, 0.169]
rotate_deg = [0.0, -18.0, 0.0]
scale = 0.165
material = { albedo = [0.73, 0.73, 0.73] }
"#;
    let scene =
        Scene::from_toml_str(toml, Path::new("<emissive box>"), Path::new(ROOT)).expect("parses");
    assert!(
        scene.lights.is_empty(),
        "the scene must be lit by emission only"
    );
    let ctx = common::context();
    let render = |gi: GiSettings| {
        let settings = RenderSettings {
            width: 48,
            height: 48,
            gi,
            ..Default::default()
        };
        render_image(&ctx, &scene, &settings).expect("renders").hdr
    };
    let hemisphere = render(GiSettings {
        method: GiMethod::Hemisphere,
        rays: 4,
        ..Default::default()
    });
    let first_bounce = render(GiSettings {
        method: GiMethod::Pathtrace,
        rays: 4,
        bounces: Bounces::Fixed(1),
        emitter_sampling: false,
        ..Default::default()
    });
    let two_bounces = render(GiSettings {
        method: GiMethod::Pathtrace,
        rays: 4,
        bounces: Bounces::Fixed(2),
        emitter_sampling: false,
        ..Default::default()
    });
    common::assert_no_validation_messages(&ctx);
    let differing = hemisphere
        .data
        .iter()
        .zip(&first_bounce.data)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "{differing} pixels differ between the hemisphere gather and the path tracer's first bounce"
    );
    let mean = |img: &HdrImage| {
        img.data.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / img.data.len() as f32
    };
    let (one, two) = (mean(&first_bounce), mean(&two_bounces));
    println!("emission-only box: mean radiance, 1 bounce {one:.5}, 2 bounces {two:.5}");
    // The second bounce is light reflected once more by walls of albedo ≤ 0.73, so it adds
    // less than the first bounce brought (power after a bounce ≤ ρ_max × power before, the box
    // being open at the front only loses more; the emitter's own pixels add the same to both
    // means, which only pulls the ratio toward 1), and in a white-walled box clearly more than
    // nothing: measured +13.5% at 48², emitter pixels included (`cargo test --test emission --
    // --nocapture`).
    assert!(
        two > one * 1.05 && two < one * 1.73,
        "2 bounces {two} against 1 bounce {one}"
    );
}

/// Outgoing radiance of a GGX floor point `p` toward `wo` under the emitter (side `a`, height
/// `d`, radiance L): midpoint quadrature of ∫ f(wi, wo) L cos_i cos_e / r² dA over the
/// rectangle (the exact BRDF `scene::ggx_brdf`), 200 x 200 cells.
fn ggx_floor_radiance(
    p: Vec3,
    wo: Vec3,
    ggx: voxgi::scene::Ggx,
    base: Vec3,
    a: f32,
    d: f32,
) -> f32 {
    let n = Vec3::Y;
    let cells = 200;
    let cell = a / cells as f32;
    let mut sum = 0.0;
    for i in 0..cells {
        for j in 0..cells {
            let q = Vec3::new(
                -a / 2.0 + (i as f32 + 0.5) * cell,
                d,
                -a / 2.0 + (j as f32 + 0.5) * cell,
            );
            let to = q - p;
            let r2 = to.length_squared();
            let wi = to / r2.sqrt();
            let cos_e = wi.y; // the emitter faces down
            let f = voxgi::scene::ggx_brdf(base, ggx, n, wi, wo).x;
            sum += f * EMISSION_W_SR_M2 * wi.dot(n) * cos_e / r2 * cell * cell;
        }
    }
    sum
}

/// A GGX metal floor (m = 1, so no diffuse term: treated as Lambert it would be black) under
/// the emitter: the path tracer's first bounce samples the GGX lobe (visible normals) and must
/// match the quadrature of the exact BRDF over the emitter, within the voxel bound (the
/// quadrature over the emitter grown by one voxel on each side, as for the Lambert floor) and
/// 5% for the noise of 16 lobe rays x 8 frames per pixel over the 8 x 8 window (measured:
/// traced 0.747, quadrature 0.679, voxel bound 0.738; the emitter covers much of the lobe, so
/// the estimate's relative sigma is a few percent per pixel and well under 1% over the window).
#[test]
fn ggx_floor_under_an_emissive_rectangle_matches_the_brdf_quadrature() {
    let (roughness, base) = (0.5, Vec3::splat(0.9));
    let scene = emitter_scene(&format!(
        "{{ albedo = {}, roughness = {roughness}, metallic = 1.0 }}",
        base.x
    ));
    let ggx = voxgi::scene::Ggx {
        roughness,
        metallic: 1.0,
    };
    let h = voxel_side_m(&scene);
    let ctx = common::context();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        gi: GiSettings {
            method: GiMethod::Pathtrace,
            rays: 32,
            bounces: Bounces::Fixed(1),
            accumulate_frames: 8,
            filter_passes: 0,
            ..Default::default()
        },
        ..Default::default()
    };
    let img = render_image(&ctx, &scene, &settings).expect("renders").hdr;
    common::assert_no_validation_messages(&ctx);
    let (mut traced, mut exact, mut largest) = (0.0, 0.0, 0.0);
    for y in SIZE / 2 - WINDOW..SIZE / 2 + WINDOW {
        for x in SIZE / 2 - WINDOW..SIZE / 2 + WINDOW {
            traced += img.data[(y * SIZE + x) as usize][0];
            let (near, far) = common::pixel_ray_points(&scene, x, y, SIZE);
            let p = near + (far - near) * (near.y / (near.y - far.y));
            let wo = (scene.camera.position - p).normalize();
            exact += ggx_floor_radiance(p, wo, ggx, base, SIDE_M, HEIGHT_M);
            largest += ggx_floor_radiance(p, wo, ggx, base, SIDE_M + 2.0 * h, HEIGHT_M - h);
        }
    }
    let n = (4 * WINDOW * WINDOW) as f32;
    let (traced, exact, largest) = (traced / n, exact / n, largest / n);
    println!("GGX floor: traced {traced:.4}, quadrature {exact:.4}, voxel bound {largest:.4}");
    assert!(
        traced > 0.95 * exact && traced < 1.05 * largest,
        "GGX floor radiance {traced} outside [{}, {}]",
        0.95 * exact,
        1.05 * largest
    );
}

//! Cached light-space passes (`graph::Cache`, `shadow.cache`): a frame that reuses the shadow
//! maps and light maps of an earlier frame is bit-identical to one that renders them again
//! (`--no-cache`), across light moves and edits, objects moving into and out of a light's
//! view, and camera moves; and the cached passes really are skipped while nothing they read
//! changed, so these tests fail if caching silently stops.

mod common;

use glam::Vec3;
use voxgi::gi::{GiMethod, GiSettings, RadianceSource};
use voxgi::render::{render_animation, render_sequence, RenderSettings, Renderer};
use voxgi::scene::{Light, Scene};

const SIZE: u32 = 32;

/// Direct light only, or the hemisphere method reading the light maps or the direct-radiance
/// volume.
const GI: [Option<RadianceSource>; 3] = [
    None,
    Some(RadianceSource::Maps),
    Some(RadianceSource::Volume),
];

fn settings(cache: bool, gi: Option<RadianceSource>) -> RenderSettings {
    let mut s = RenderSettings {
        width: SIZE,
        height: SIZE,
        ..Default::default()
    };
    s.shadow.cache = cache;
    if let Some(radiance_source) = gi {
        s.gi = GiSettings {
            method: GiMethod::Hemisphere,
            radiance_source,
            ..Default::default()
        };
    }
    s
}

fn cornell_mover() -> Scene {
    common::animated_scene()
}

/// The mover scene's spot light, moved by `offset` and its intensity scaled by `scale`.
fn edited(scene: &Scene, offset: Vec3, scale: f32) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        if let Light::Spot {
            position,
            intensity_w_sr,
            ..
        } = l
        {
            *position += offset;
            *intensity_w_sr *= scale;
        }
    }
    s
}

/// Asserts that two frame lists are bit-identical, naming the first frame that differs.
fn assert_identical(cached: &[voxgi::eval::HdrImage], uncached: &[voxgi::eval::HdrImage]) {
    assert_eq!(cached.len(), uncached.len());
    for (i, (a, b)) in cached.iter().zip(uncached).enumerate() {
        let same = a
            .data
            .iter()
            .flatten()
            .zip(b.data.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same, "frame {i} differs between cache on and off");
    }
}

/// A sequence of frames with one renderer, as the viewer makes them: still, camera moved
/// (the light-space passes reuse), light moved, light edited (intensity), light moved back,
/// camera moved again. Rendered with the cache on and off, every frame is bit-identical, with
/// direct light only and with the hemisphere method (which reads the light maps).
#[test]
fn cached_sequences_match_uncached_across_light_and_camera_changes() {
    let scene = cornell_mover();
    let mut camera_moved = scene.clone();
    camera_moved.camera.position += Vec3::new(0.05, -0.02, 0.1);
    let light_moved = edited(&camera_moved, Vec3::new(0.06, -0.03, 0.02), 1.0);
    let light_edited = edited(&light_moved, Vec3::ZERO, 2.5);
    let light_back = edited(&light_edited, Vec3::new(-0.06, 0.03, -0.02), 1.0);
    let mut camera_again = light_back.clone();
    camera_again.camera.position += Vec3::new(-0.08, 0.03, 0.05);
    let then = [
        scene.clone(),
        camera_moved,
        light_moved,
        light_edited,
        light_back,
        camera_again,
    ];
    let ctx = common::context();
    for gi in GI {
        let run =
            |cache| render_sequence(&ctx, &scene, &settings(cache, gi), 2, &then).expect("renders");
        let (cached, uncached) = (run(true), run(false));
        assert_identical(
            std::slice::from_ref(&cached.warm),
            std::slice::from_ref(&uncached.warm),
        );
        assert_identical(&cached.frames, &uncached.frames);
        // The light changes must show: otherwise this test could not tell a stale map.
        assert_ne!(
            cached.frames[1].data, cached.frames[2].data,
            "moving the light changed nothing (gi {gi:?})"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// The mover's cube moves into and out of the spot light's view (keyframed from inside the
/// box at t = 0 to partly outside at t = 1) and is still between some frames: every frame of
/// the animation is bit-identical with the cache on and off.
#[test]
fn cached_animation_matches_uncached() {
    let scene = cornell_mover();
    let times = [0.0, 0.0, 0.4, 0.4, 0.4, 1.0, 1.3, 1.3];
    let ctx = common::context();
    for gi in GI {
        let run = |cache| render_animation(&ctx, &scene, &settings(cache, gi), &times);
        let cached = run(true).expect("renders");
        let uncached = run(false).expect("renders");
        assert_identical(&cached, &uncached);
    }
    common::assert_no_validation_messages(&ctx);
}

/// The passes are skipped while their inputs stay: over 6 frames of a still scene, then 6
/// with the camera moving, the shadow maps and light maps render once (the spot light has
/// no cascades, so nothing they draw depends on the camera); a moved light renders them
/// once more, an edited intensity re-renders only the light maps (the depth is the same),
/// and with `--no-cache` there is no cache to count. `voxgi graph` marks them `(cached)`; with
/// the cache off one `shadow_depth` pass draws every layer, as before.
#[test]
fn cached_passes_are_skipped_while_their_inputs_stay() {
    let scene = cornell_mover();
    let ctx = common::context();
    let mut renderer =
        Renderer::new(&ctx, &scene, settings(true, Some(RadianceSource::Maps))).expect("renderer");
    let g = renderer.graph();
    let compiled = g
        .compile(&voxgi::graph::EstimateOracle)
        .expect("graph compiles");
    let text = compiled.dump_text(&g);
    for pass in ["shadow_depth[0] (cached)", "light_map (cached)"] {
        assert!(text.contains(pass), "graph lacks {pass}:\n{text}");
    }
    let exec = voxgi::graph::GraphExecutor::new(&ctx, g, voxgi::vk::MAX_FRAMES_IN_FLIGHT)
        .expect("executor");
    // The spot light has one view: one shadow-map layer.
    let counts = |r: &Renderer| {
        let c = r.cache_counts();
        let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["shadow map 0", "light maps"]);
        (c[0].1, c[1].1)
    };
    voxgi::graph::run_frames(&ctx, &exec, 6, 0, |slot| renderer.write_frame(slot)).expect("runs");
    assert_eq!(counts(&renderer), ((1, 5), (1, 5)));
    let mut flown = scene.clone();
    let mut k = 0;
    voxgi::graph::run_frames(&ctx, &exec, 6, 0, |slot| {
        k += 1;
        flown.camera.position = scene.camera.position + Vec3::new(0.01 * k as f32, 0.0, 0.02);
        renderer.prepare(&flown).expect("prepares");
        renderer.write_frame(slot)
    })
    .expect("runs");
    assert_eq!(counts(&renderer), ((1, 11), (1, 11)));
    for (changed, shadow_renders) in [
        (edited(&flown, Vec3::new(0.05, 0.0, 0.0), 1.0), 2),
        (edited(&flown, Vec3::new(0.05, 0.0, 0.0), 3.0), 2),
    ] {
        renderer.prepare(&changed).expect("prepares");
        voxgi::graph::run_frames(&ctx, &exec, 2, 0, |slot| renderer.write_frame(slot))
            .expect("runs");
        assert_eq!(counts(&renderer).0 .0, shadow_renders);
    }
    assert_eq!(counts(&renderer).1 .0, 3, "light maps: moved, then edited");
    drop(exec);
    let uncached =
        Renderer::new(&ctx, &scene, settings(false, Some(RadianceSource::Maps))).expect("renderer");
    assert!(uncached.cache_counts().is_empty());
    let g = uncached.graph();
    let text = g
        .compile(&voxgi::graph::EstimateOracle)
        .expect("compiles")
        .dump_text(&g);
    assert!(!text.contains("(cached)"), "{text}");
    assert!(text.contains("] shadow_depth\n"), "{text}");
    common::assert_no_validation_messages(&ctx);
}

/// The direct-radiance volume (`--gi-radiance volume`) is a cached image of the graph's too,
/// computed again only when the lights or the objects changed: not while the camera moves
/// (before, every camera move restarted accumulation and recomputed it, 675 ms per frame at
/// 128³ on lavapipe), and in every frame in which the mover's cube moved, with temporal
/// accumulation too (before, a history that outlived a moving object kept its stale volume).
#[test]
fn the_radiance_volume_renders_after_light_and_object_changes_only() {
    let scene = cornell_mover();
    let ctx = common::context();
    for temporal in [false, true] {
        let mut s = settings(true, Some(RadianceSource::Volume));
        s.gi.temporal = temporal;
        let mut renderer = Renderer::new(&ctx, &scene, s).expect("renderer");
        let exec = voxgi::graph::GraphExecutor::new(
            &ctx,
            renderer.graph(),
            voxgi::vk::MAX_FRAMES_IN_FLIGHT,
        )
        .expect("executor");
        let renders = |r: &Renderer| {
            let c = r.cache_counts();
            let volume = c.iter().find(|(n, _)| n == "direct radiance volume");
            volume.expect("the volume is cached").1 .0
        };
        let mut flown = scene.clone();
        let mut k = 0;
        voxgi::graph::run_frames(&ctx, &exec, 4, 0, |slot| {
            k += 1;
            flown.camera.position = scene.camera.position + Vec3::new(0.01 * k as f32, 0.0, 0.02);
            renderer.prepare(&flown).expect("prepares");
            renderer.write_frame(slot)
        })
        .expect("runs");
        assert_eq!(renders(&renderer), 1, "camera moves (temporal {temporal})");
        let moved = edited(&flown, Vec3::new(0.05, 0.0, 0.0), 1.0);
        renderer.prepare(&moved).expect("prepares");
        voxgi::graph::run_frames(&ctx, &exec, 2, 0, |slot| renderer.write_frame(slot))
            .expect("runs");
        assert_eq!(renders(&renderer), 2, "a moved light (temporal {temporal})");
        for t_s in [0.2, 0.4, 0.6] {
            renderer.settings.time_s = t_s;
            renderer.prepare(&moved).expect("prepares");
            voxgi::graph::run_frames(&ctx, &exec, 1, 0, |slot| renderer.write_frame(slot))
                .expect("runs");
        }
        assert_eq!(
            renders(&renderer),
            5,
            "the cube moved (temporal {temporal})"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

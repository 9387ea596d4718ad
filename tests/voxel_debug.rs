//! The voxel debug views (`voxgi render --debug voxels|steps|level|albedo`): camera rays
//! through the GPU column image. Checks on read-back pixels: background black, the Cornell
//! floor lit by its +y face, step counts within the iteration cap, the hierarchical view equal
//! to the exact walk, coarser levels covering finer ones, the albedo view showing each wall's
//! material, and the atlas view (`--debug atlas`) drawing exactly the CPU atlas's valid
//! texels. Validation and synchronization validation on.

mod common;

use glam::{Vec3, Vec4Swizzles};
use std::collections::HashSet;
use std::path::Path;
use voxgi::eval::HdrImage;
use voxgi::render::{render_image, RenderOutput, RenderSettings};
use voxgi::scene::{builtin, Scene};
use voxgi::voxel::atlas::AtlasCache;
use voxgi::voxel::atlas_view::object_atlas;
use voxgi::voxel::debug_view::{debug_stats, DebugSettings, DebugView};
use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};

const SIZE: u32 = 96;

fn render(scene: &Scene, view: DebugView, level: u32) -> RenderOutput {
    render_with(scene, view, level, Voxelizer::Triangle)
}

fn render_with(scene: &Scene, view: DebugView, level: u32, voxelizer: Voxelizer) -> RenderOutput {
    let ctx = common::context();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        debug: Some(DebugSettings {
            view,
            level,
            ..Default::default()
        }),
        voxels: Some(VoxelSettings {
            voxelizer,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = render_image(&ctx, scene, &settings).expect("renders the debug view");
    common::assert_no_validation_messages(&ctx);
    assert!(out.live_passes.iter().any(|p| p == "voxel_debug"));
    // Only the albedo view needs the albedo volume, written by the voxelizer's own method.
    let live = |name: &str| out.live_passes.iter().any(|p| p == name);
    let albedo = view == DebugView::Albedo;
    assert_eq!(
        (live("voxelize_attributes"), live("voxelize_atlas_resolve")),
        (
            albedo && voxelizer == Voxelizer::Triangle,
            albedo && voxelizer == Voxelizer::Atlas
        ),
        "{view:?}, {voxelizer:?}: {:?}",
        out.live_passes
    );
    for culled in ["deferred_direct", "tonemap", "gbuffer", "shadow_depth"] {
        assert!(
            // The cached shadow maps are drawn per layer, `shadow_depth[v]`.
            !out.live_passes
                .iter()
                .any(|p| p == culled || p.starts_with(&format!("{culled}["))),
            "{culled} must be culled in a debug view: {:?}",
            out.live_passes
        );
    }
    assert_eq!(out.ldr.len(), (SIZE * SIZE * 4) as usize);
    out
}

fn value(img: &HdrImage, x: u32, y: u32) -> [f32; 3] {
    img.data[(y * img.width + x) as usize]
}

/// The pixel through which the camera sees world point `p`.
fn pixel_of(scene: &Scene, p: Vec3) -> (u32, u32) {
    let clip = scene.camera.view_proj(1.0) * p.extend(1.0);
    let ndc = clip.xy() / clip.w;
    let px = (ndc + 1.0) * 0.5 * SIZE as f32;
    (px.x as u32, px.y as u32)
}

#[test]
fn cornell_voxels_view_lights_the_floor_and_equals_the_exact_walk() {
    let scene = builtin("cornell").expect("cornell");
    let voxels = render(&scene, DebugView::Voxels, 0);
    // Floor in front of the tall block: entered through its +y face, N.L = 0.6 / |L| with the
    // light over the camera's shoulder (-forward + 0.6 up - 0.4 right), shade 0.15 + 0.85 N.L,
    // edges darkened to at most 0.6 of that.
    let n_dot_l = 0.6 / (1.0f32 + 0.36 + 0.16).sqrt();
    let lit = 0.15 + 0.85 * n_dot_l;
    for p in [Vec3::new(0.45, 0.0, 0.1), Vec3::new(0.1, 0.0, 0.05)] {
        let (x, y) = pixel_of(&scene, p);
        let v = value(&voxels.hdr, x, y)[0];
        assert!(
            (0.6 * lit - 1e-3..=lit + 1e-3).contains(&v),
            "floor point {p} at pixel ({x}, {y}): shade {v}, expected within [{}, {lit}]",
            0.6 * lit
        );
        let i = ((y * SIZE + x) * 4) as usize;
        assert!(
            voxels.ldr[i] > 60,
            "floor pixel ({x}, {y}) is lit in the PNG"
        );
    }
    // The hierarchical traversal and the exact walk over level 0 see the same voxels.
    let walk = render(&scene, DebugView::Level, 0);
    let differ = (voxels.hdr.data.iter().zip(&walk.hdr.data))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differ, 0, "hierarchical and DDA debug images differ");
    assert_eq!(voxels.ldr, walk.ldr);
}

#[test]
fn cornell_albedo_view_shows_each_walls_material() {
    for voxelizer in [Voxelizer::Triangle, Voxelizer::Atlas] {
        cornell_albedo_view_with(voxelizer);
    }
}

fn cornell_albedo_view_with(voxelizer: Voxelizer) {
    let scene = builtin("cornell").expect("cornell");
    let albedo_of = |name: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name.contains(name))
            .unwrap_or_else(|| panic!("material {name}"))
            .albedo
    };
    let albedo = render_with(&scene, DebugView::Albedo, 0, voxelizer);
    // Mid-wall points above both blocks, seen past them: the red wall at x = 0.55 m (left in
    // the image), the green one at x = 0, the white back wall at z = 0.56.
    let walls = [
        ("cornell_red", Vec3::new(0.55, 0.42, 0.4), 0),
        ("cornell_green", Vec3::new(0.0, 0.42, 0.4), 1),
        ("cornell_white", Vec3::new(0.28, 0.42, 0.559), 3),
    ];
    // RGBA8 UNORM volume: half a step of rounding, plus float slack; the atlas averages its
    // points' albedo in f16 sums first.
    let tol = match voxelizer {
        Voxelizer::Triangle => 0.5 / 255.0 + 1e-4,
        Voxelizer::Atlas => 1.5 / 255.0,
    };
    for (name, p, dominant) in walls {
        let kd = albedo_of(name);
        let (x, y) = pixel_of(&scene, p);
        let v = Vec3::from(value(&albedo.hdr, x, y));
        assert!(
            (v - kd).abs().max_element() <= tol,
            "{voxelizer:?}: {name} at pixel ({x}, {y}): albedo {v}, material Kd {kd}"
        );
        let i = ((y * SIZE + x) * 4) as usize;
        let rgb = &albedo.ldr[i..i + 3];
        if dominant < 3 {
            let others = (0..3).filter(|&c| c != dominant);
            for c in others {
                assert!(
                    rgb[dominant] > rgb[c] + 40,
                    "{name} pixel ({x}, {y}) is not dominated by channel {dominant}: {rgb:?}"
                );
            }
        } else {
            // White, shaded: gray and lit.
            let gray = rgb.iter().all(|&c| c.abs_diff(rgb[0]) <= 1);
            assert!(gray && rgb[0] > 40, "{name}: {rgb:?}");
        }
    }
    // The same rays hit the same voxels as the voxels view, and every hit voxel has an albedo
    // (no Cornell material is black): the volume covers every bit.
    let voxels = render_with(&scene, DebugView::Voxels, 0, voxelizer);
    for (i, (a, v)) in albedo.hdr.data.iter().zip(&voxels.hdr.data).enumerate() {
        let albedo_hit = a.iter().any(|&c| c > 0.0);
        assert_eq!(
            albedo_hit,
            v[0] > 0.0,
            "{voxelizer:?}: pixel {i}: albedo {a:?}, shade {v:?}"
        );
    }
    let st = debug_stats(DebugView::Albedo, &albedo.hdr);
    assert_eq!(st.hits, debug_stats(DebugView::Voxels, &voxels.hdr).hits);
}

#[test]
fn atlas_view_draws_exactly_the_cpu_atlas_valid_texels() {
    let scene = builtin("cornell").expect("cornell");
    let object = scene.find_object("tall_block").expect("the tall block");
    assert_eq!(scene.find_object(&object.to_string()).ok(), Some(object));
    let grid = VoxelSettings::default()
        .grid_for(&scene, 0.0)
        .expect("grid");
    let atlas = object_atlas(&scene, 0.0, &grid, object, &mut AtlasCache::default())
        .expect("the block's atlas");
    let cpu: HashSet<(u32, u32)> = (0..atlas.triangles.len())
        .flat_map(|t| atlas.texels(t))
        .collect();
    // One pixel per texel plus a margin that shows the background past the atlas.
    let (w, h) = (atlas.width + 8, atlas.height + 8);
    let ctx = common::context();
    let settings = RenderSettings {
        width: w,
        height: h,
        debug: Some(DebugSettings {
            view: DebugView::Atlas,
            object,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = render_image(&ctx, &scene, &settings).expect("renders the atlas view");
    common::assert_no_validation_messages(&ctx);
    assert!(out.live_passes.iter().any(|p| p == "atlas_positions"));
    assert!(out.live_passes.iter().any(|p| p == "atlas_debug"));
    for unneeded in ["voxelize_triangles", "voxel_debug", "gbuffer", "tonemap"] {
        assert!(
            !out.live_passes.iter().any(|p| p == unneeded),
            "{unneeded} runs in the atlas view: {:?}",
            out.live_passes
        );
    }
    let mut gpu = HashSet::new();
    let mut colors = HashSet::new();
    for (i, p) in out.hdr.data.iter().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let rgb = &out.ldr[i * 4..i * 4 + 3];
        if x >= atlas.width || y >= atlas.height {
            assert_eq!(p[0], -1.0, "pixel ({x}, {y}) is past the atlas");
            continue;
        }
        assert_eq!((p[1], p[2]), (x as f32, y as f32), "zoom 1: pixel = texel");
        if p[0] > 0.5 {
            gpu.insert((x, y));
            colors.insert([rgb[0], rgb[1], rgb[2]]);
            assert!(
                rgb.iter().any(|&c| c >= 38),
                "valid texel ({x}, {y}) is lit: {rgb:?}"
            );
        } else {
            assert_eq!(rgb, &[0, 0, 0], "invalid texel ({x}, {y}) is black");
        }
    }
    let only_gpu: Vec<_> = gpu.difference(&cpu).take(5).collect();
    let only_cpu: Vec<_> = cpu.difference(&gpu).take(5).collect();
    assert_eq!(
        gpu.len(),
        cpu.len(),
        "valid texels: GPU {} vs CPU {}; only GPU e.g. {only_gpu:?}, only CPU e.g. {only_cpu:?}",
        gpu.len(),
        cpu.len()
    );
    assert_eq!(
        gpu, cpu,
        "same count, different texels: {only_gpu:?} {only_cpu:?}"
    );
    let coverage = gpu.len() as f64 / f64::from(atlas.width * atlas.height);
    assert!(coverage > 0.2, "coverage {coverage}");
    // Positions as colors: a gradient over the block's faces, not one flat color.
    assert!(colors.len() > 1000, "{} distinct colors", colors.len());
    let described = out.debug_description.expect("a description");
    assert!(
        described.contains(&format!("{} valid texels", cpu.len())),
        "{described}"
    );
}

#[test]
fn atlas_view_names_the_objects_when_one_is_missing() {
    let scene = builtin("cornell").expect("cornell");
    let err = scene
        .find_object("teapot")
        .expect_err("no teapot in the box");
    let msg = err.to_string();
    assert!(
        msg.contains("'tall_block'") && msg.contains("--object"),
        "{msg}"
    );
    assert!(scene.find_object("3").is_err(), "3 objects: indices 0..=2");
}

#[test]
fn cornell_steps_view_stays_within_the_iteration_cap() {
    let scene = builtin("cornell").expect("cornell");
    let steps = render(&scene, DebugView::Steps, 0);
    let voxels = render(&scene, DebugView::Voxels, 0);
    let cap = DebugSettings::default().traversal.max_iterations;
    let mut hits = 0;
    for (s, v) in steps.hdr.data.iter().zip(&voxels.hdr.data) {
        let (n, hit, ran_out) = (s[0], s[1] > 0.5, s[2] > 0.5);
        assert_eq!(n.fract(), 0.0, "step counts are integers");
        assert!(n <= cap as f32, "{n} steps exceed the cap {cap}");
        assert!(!ran_out, "no Cornell ray runs out of {cap} iterations");
        assert_eq!(hit, v[0] > 0.0, "steps and voxels views agree on hits");
        if hit {
            hits += 1;
            assert!(n >= 1.0, "a hit takes at least one step");
        }
    }
    let st = debug_stats(DebugView::Steps, &steps.hdr);
    assert_eq!(st.hits, hits);
    assert!(
        hits as f32 > 0.8 * (SIZE * SIZE) as f32,
        "the box fills the view"
    );
    assert!(st.mean_steps > 1.0 && st.max_steps <= cap);
}

#[test]
fn coarser_levels_cover_every_finer_hit() {
    let scene = builtin("cornell").expect("cornell");
    let fine = render(&scene, DebugView::Level, 0);
    let coarse = render(&scene, DebugView::Level, 3);
    let (f, c) = (
        debug_stats(DebugView::Level, &fine.hdr),
        debug_stats(DebugView::Level, &coarse.hdr),
    );
    for (a, b) in fine.hdr.data.iter().zip(&coarse.hdr.data) {
        assert!(a[0] == 0.0 || b[0] > 0.0, "a level-0 hit missed at level 3");
    }
    assert!(c.hits >= f.hits);
}

#[test]
fn background_is_black_around_a_lone_cube() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let scene = Scene::from_toml_str(
        r#"
[camera]
position = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 40.0
near = 0.1
far = 20.0

[[objects]]
name = "cube"
builtin = "cube"
rotate_deg = [20.0, 30.0, 0.0]
"#,
        Path::new("<test scene>"),
        &dir,
    )
    .expect("test scene parses");
    for view in [
        DebugView::Voxels,
        DebugView::Steps,
        DebugView::Level,
        DebugView::Albedo,
    ] {
        let out = render(&scene, view, 1);
        let center = value(&out.hdr, SIZE / 2, SIZE / 2);
        let hit = if view == DebugView::Steps {
            center[1] > 0.5 && center[0] >= 1.0
        } else {
            center[0] > 0.0
        };
        assert!(hit, "{view:?}: the center pixel sees the cube: {center:?}");
        for (x, y) in [(0, 0), (SIZE - 1, 0), (0, SIZE - 1), (SIZE - 1, SIZE - 1)] {
            let i = ((y * SIZE + x) * 4) as usize;
            assert_eq!(
                &out.ldr[i..i + 4],
                &[0, 0, 0, 255],
                "{view:?}: corner ({x}, {y}) is background"
            );
        }
    }
}

#[test]
fn a_level_beyond_the_hierarchy_is_an_error() {
    let ctx = common::context();
    let settings = RenderSettings {
        width: 8,
        height: 8,
        debug: Some(DebugSettings {
            view: DebugView::Level,
            level: 40,
            ..Default::default()
        }),
        ..Default::default()
    };
    let scene = builtin("cornell").expect("cornell");
    let err = render_image(&ctx, &scene, &settings)
        .err()
        .expect("level 40 is rejected");
    assert!(err.to_string().contains("--debug-level"), "{err}");
}

/// A debug view replaces the lit image, so a GI method chosen with it (as the built-in Cornell
/// box's `[gi]` table chooses the path tracer) adds no passes: before, the albedo view and the
/// path tracer both declared `voxelize_attributes` and the graph refused the frame.
#[test]
fn a_debug_view_with_a_gi_method_renders_the_view_alone() {
    let ctx = common::context();
    let scene = builtin("cornell").expect("cornell");
    for view in [DebugView::Albedo, DebugView::Voxels] {
        let settings = RenderSettings {
            width: 32,
            height: 32,
            debug: Some(DebugSettings {
                view,
                ..Default::default()
            }),
            gi: voxgi::gi::GiSettings {
                method: voxgi::gi::GiMethod::Pathtrace,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = render_image(&ctx, &scene, &settings).expect("renders the debug view");
        assert!(out.live_passes.iter().any(|p| p == "voxel_debug"));
        assert!(
            !out.live_passes.iter().any(|p| p.starts_with("gi_")),
            "{view:?}: {:?}",
            out.live_passes
        );
    }
    common::assert_no_validation_messages(&ctx);
}

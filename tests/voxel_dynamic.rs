//! Dynamic objects move in the voxel grid: the per-frame triangle buffer follows the scene's
//! animation, every hierarchy level equals the CPU reference at each frame's time bit for bit,
//! frames where nothing moved record no voxel work, and a scene without dynamic objects has
//! no per-frame voxel passes. Validation and synchronization validation on.

mod common;

use std::path::Path;
use voxgi::graph::{Access, GraphExecutor, RenderGraph};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{builtin, Scene};
use voxgi::vk::{vk, FrameLoop, MAX_FRAMES_IN_FLIGHT};
use voxgi::voxel::bits::mip_extent;
use voxgi::voxel::gpu::{image_extent, readback_buffer, VoxelFrame, VoxelSettings};
use voxgi::voxel::{voxelize_scene, BitGrid, BitHierarchy};

/// Static Cornell walls and a keyframed cube that moves and turns (and leaves the box, so
/// part of it is clipped at t = 1).
fn animated_scene() -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Scene::from_toml_str(
        r#"
[camera]
position = [0.278, 0.273, -0.800]
target = [0.278, 0.273, 0.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 39.3
near = 0.01
far = 10.0

[[objects]]
name = "walls"
builtin = "cornell_walls"

[[objects]]
name = "mover"
builtin = "cube"
scale = 0.12

[objects.animation]
loop = false

[[objects.animation.keyframes]]
time_s = 0.0
translate = [0.2, 0.15, 0.2]
rotate_deg = [0.0, 0.0, 0.0]

[[objects.animation.keyframes]]
time_s = 1.0
translate = [0.45, 0.35, 0.4]
rotate_deg = [30.0, 45.0, 10.0]
"#,
        Path::new("<animated test scene>"),
        &dir,
    )
    .expect("test scene parses")
}

/// The CPU reference hierarchy of the whole scene at `t_s` on `frame`'s grid.
fn reference(scene: &Scene, frame: &VoxelFrame, t_s: f32) -> BitHierarchy {
    let grid = &frame.voxels.grid;
    let mut bits = BitGrid::for_grid(grid);
    voxelize_scene(grid, &mut bits, scene, t_s).expect("CPU voxelization");
    BitHierarchy::build(bits)
}

/// Level `l` of the GPU read-back, cropped to the CPU level size.
fn crop(bytes: &[u8], size: (u32, u32), layers: u32, cpu: &BitGrid) -> BitGrid {
    let full = BitGrid::from_gpu_bytes(size.0, size.1, layers, bytes).expect("read-back size");
    let mut out = BitGrid::new(cpu.res_x(), cpu.res_y(), layers);
    for layer in 0..layers {
        for y in 0..size.1 {
            for x in 0..size.0 {
                let c = full.column(x, y, layer);
                if x < cpu.res_x() && y < cpu.res_y() {
                    *out.column_mut(x, y, layer) = c;
                } else {
                    assert_eq!(c, [0; 4], "padding texel ({x},{y}) is set");
                }
            }
        }
    }
    out
}

#[test]
fn animated_object_voxels_follow_the_cpu_reference_per_frame() {
    let ctx = common::context();
    let scene = animated_scene();
    let mut frame =
        VoxelFrame::new(&ctx, &scene, 0.0, &VoxelSettings::default()).expect("voxel frame");
    assert!(frame.has_frame_passes());
    let grid = frame.voxels.grid;
    let (w, h) = image_extent(&grid);
    let layers = grid.layers();
    let levels = frame.voxels.mip_levels();
    let sizes: Vec<(u32, u32)> = (0..levels)
        .map(|l| ((w >> l).max(1), (h >> l).max(1)))
        .collect();
    let readbacks: Vec<_> = sizes
        .iter()
        .map(|&(lw, lh)| {
            readback_buffer(&ctx, "voxel readback", u64::from(lw * lh * layers) * 16)
                .expect("readback buffer")
        })
        .collect();

    let mut g = RenderGraph::new();
    let image = frame.add_passes(&mut g);
    let outs: Vec<_> = readbacks
        .iter()
        .map(|b| g.import_buffer(b, Access::HostRead))
        .collect();
    let mut pass = g
        .add_pass("voxel_readback")
        .read(image, Access::TransferRead);
    for &o in &outs {
        pass = pass.write(o, Access::TransferWrite);
    }
    let sizes_c = sizes.clone();
    pass.record(move |ctx| {
        for (l, (&o, &(lw, lh))) in outs.iter().zip(&sizes_c).enumerate() {
            ctx.cmd.copy_image_to_buffer(
                ctx.image(image).raw,
                vk::Extent3D {
                    width: lw,
                    height: lh,
                    depth: 1,
                },
                l as u32,
                layers,
                ctx.buffer(o).raw,
            );
        }
    });
    let exec = GraphExecutor::new(&ctx, g, MAX_FRAMES_IN_FLIGHT).expect("graph compiles");
    let mut frames = FrameLoop::new(
        &ctx,
        MAX_FRAMES_IN_FLIGHT,
        exec.compiled().order.len() as u32,
    )
    .expect("frame loop");

    let refs = [
        (0.0, reference(&scene, &frame, 0.0)),
        (1.0, reference(&scene, &frame, 1.0)),
    ];
    assert_ne!(
        refs[0].1.level(0),
        refs[1].1.level(0),
        "the object moves between t = 0 and t = 1"
    );
    // (time, whether the frame re-voxelizes): moved, moved, still, moved back, still, and a
    // time past the last key (held pose = t 1) after t 1. Slots alternate, so in frames 2
    // and 6 slot 0 still holds the t = 0 triangles: had their passes recorded, the grid
    // would show t = 0 and the comparison with t = 1 would fail.
    let plan = [
        (0.0, true),
        (1.0, true),
        (1.0, false),
        (0.0, true),
        (0.0, false),
        (1.0, true),
        (5.0, false),
    ];
    for (i, &(t, expect_run)) in plan.iter().enumerate() {
        let slot = frames.current_slot();
        let (_, cmd, ts, _) = frames.begin(&ctx).expect("frame begins");
        let ran = frame.update(t, slot).expect("update");
        assert_eq!(ran, expect_run, "frame {i} at t = {t}");
        exec.record(&cmd, slot, ts);
        frames.submit(&ctx, &[], &[]).expect("submit");
        ctx.wait_idle().expect("wait idle");
        let want = &refs[usize::from(t != 0.0)].1;
        for (l, (b, &size)) in readbacks.iter().zip(&sizes).enumerate() {
            let cpu = want.level(l as u32);
            assert_eq!(
                (cpu.res_x(), cpu.res_y()),
                (
                    mip_extent(grid.res_x(), l as u32),
                    mip_extent(grid.res_y(), l as u32)
                )
            );
            let n = (size.0 * size.1 * layers * 16) as usize;
            let got = crop(&b.mapped().expect("host-visible")[..n], size, layers, cpu);
            assert!(
                &got == cpu,
                "frame {i} (t = {t}, slot {slot}): level {l} differs from the CPU reference"
            );
        }
    }
    frames.finish(&ctx).expect("frames finish");
    frames.destroy(&ctx);
    exec.destroy(&ctx);
    for b in readbacks {
        ctx.destroy_buffer(b);
    }
    frame.destroy(&ctx);
    common::assert_no_validation_messages(&ctx);
}

fn voxel_passes(scene: &Scene, time_s: f32) -> Vec<String> {
    let ctx = common::context();
    let settings = RenderSettings {
        width: 16,
        height: 16,
        time_s,
        voxels: Some(VoxelSettings::default()),
        ..Default::default()
    };
    let out = render_image(&ctx, scene, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    out.live_passes
        .into_iter()
        .filter(|p| p.starts_with("voxel"))
        .collect()
}

#[test]
fn only_scenes_with_dynamic_objects_have_per_frame_voxel_passes() {
    let cornell = builtin("cornell").expect("cornell");
    assert_eq!(voxel_passes(&cornell, 0.0), Vec::<String>::new());
    let animated = voxel_passes(&animated_scene(), 0.5);
    for p in [
        "voxel_copy_static",
        "voxelize_triangles",
        "voxel_store",
        "voxel_mip_1",
    ] {
        assert!(animated.iter().any(|n| n == p), "{p} missing: {animated:?}");
    }
}

//! Dynamic objects move in the voxel grid: the per-frame triangle buffer follows the scene's
//! animation, every hierarchy level equals the CPU reference at each frame's time bit for bit,
//! frames where nothing moved record no voxel work, and a scene without dynamic objects has
//! no per-frame voxel passes. Validation and synchronization validation on.

mod common;

use voxgi::graph::{GraphExecutor, RenderGraph};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{builtin, Scene};
use voxgi::vk::{FrameLoop, MAX_FRAMES_IN_FLIGHT};
use voxgi::voxel::gpu::VoxelSettings;
use voxgi::voxel::VoxelFrame;
use voxgi::voxel::{voxelize_scene, BitGrid, BitHierarchy};

/// The CPU reference hierarchy of the whole scene at `t_s` on `frame`'s grid.
fn reference(scene: &Scene, frame: &VoxelFrame, t_s: f32) -> BitHierarchy {
    let grid = &frame.voxels.grid;
    let mut bits = BitGrid::for_grid(grid);
    voxelize_scene(grid, &mut bits, scene, t_s).expect("CPU voxelization");
    BitHierarchy::build(bits)
}

/// Level `l` of the GPU read-back, cropped to the CPU level size.
#[test]
fn animated_object_voxels_follow_the_cpu_reference_per_frame() {
    let ctx = common::context();
    let scene = common::animated_scene();
    let mut frame =
        VoxelFrame::new(&ctx, &scene, 0.0, &VoxelSettings::default()).expect("voxel frame");
    assert!(frame.has_frame_passes());
    let grid = frame.voxels.grid;
    let readback = common::VoxelReadback::new(&ctx, &grid, frame.voxels.mip_levels());

    let mut g = RenderGraph::new();
    let image = frame.add_passes(&mut g);
    readback.add_pass(&mut g, image);
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
        for (l, got) in readback.levels(&grid).iter().enumerate() {
            let cpu = want.level(l as u32);
            assert!(
                got == cpu,
                "frame {i} (t = {t}, slot {slot}): level {l} differs from the CPU reference"
            );
        }
    }
    frames.finish(&ctx).expect("frames finish");
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
    let animated = voxel_passes(&common::animated_scene(), 0.5);
    for p in [
        "voxel_copy_static",
        "voxelize_triangles",
        "voxel_store",
        "voxel_mip_1",
    ] {
        assert!(animated.iter().any(|n| n == p), "{p} missing: {animated:?}");
    }
}

/// `voxgi bench dynamic` (Thiedemann 2010 §8.2, Figs. 41/42) measures what it says: with no
/// animated object the static scene's bits are made once, before the frames, and no frame
/// runs a bit pass; the attribute passes are skipped (what remains is the timestamp pair of
/// a skipped pass, 0.015 ms on lavapipe against hundreds of ms for a pass that runs: bound
/// 1/10 of the 3-bunny row's). With 3 animated bunnies every measured frame voxelizes them,
/// with both voxelizers, and the path tracer's frames write its attribute volumes too.
#[test]
fn the_dynamic_objects_benchmark_revoxelizes_only_what_moves() {
    let ctx = common::context();
    let desc = voxgi::bench::DynamicBenchDesc {
        animated: vec![0, 3],
        size: 16,
        frames: 2,
        warmup: 1,
    };
    let report = voxgi::bench::bench_dynamic(&ctx, &desc).expect("bench runs");
    assert_eq!(report.rows.len(), 8);
    let (still, moving) = report.rows.split_at(4);
    for (s, m) in still.iter().zip(moving) {
        let what = format!("{} {}", m.voxelizer, m.method);
        assert_eq!((s.animated, m.animated), (0, 3));
        assert_eq!(
            s.bits_ms, 0.0,
            "{what}: a bit pass ran without animated objects"
        );
        assert!(
            m.bits_ms > 0.0,
            "{what}: no bit pass ran with animated objects"
        );
        if m.method == "pathtrace" {
            assert!(
                s.attributes_ms < 0.1 * m.attributes_ms,
                "{what}: attributes {} ms still against {} ms moving",
                s.attributes_ms,
                m.attributes_ms
            );
        } else {
            assert_eq!(
                m.attributes_ms, 0.0,
                "{what}: attribute volumes without a reader"
            );
        }
    }
    common::assert_no_validation_messages(&ctx);
}

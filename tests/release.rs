//! GPU objects release themselves when dropped (docs/ARCHITECTURE.md, "Errors, ownership,
//! tests"): with no submission in flight at once, otherwise once the frame that may use them
//! completed. The fixture's teardown check fails the test if an object was destroyed while a
//! command buffer still used it (the validation layers report that) or never freed.

mod common;

use voxgi::graph::{Access, GraphExecutor, RenderGraph};
use voxgi::vk::FrameLoop;

#[test]
fn an_object_dropped_with_nothing_in_flight_is_destroyed_at_once() {
    let ctx = common::context();
    let buffer = common::transfer_buffer(&ctx, "idle");
    drop(buffer);
    assert_eq!(ctx.pending_releases(), 0);
}

#[test]
fn an_object_dropped_while_its_frame_is_in_flight_waits_for_the_frame() {
    let ctx = common::context();
    let target = common::transfer_buffer(&ctx, "in flight");
    let mut g = RenderGraph::new();
    let out = g.import_buffer(&target, Access::HostRead);
    g.add_pass("fill")
        .write(out, Access::TransferWrite)
        .record(move |p| p.cmd.fill_buffer(p.buffer(out).raw, 7));
    let exec = GraphExecutor::new(&ctx, g, 1).expect("graph");
    let mut frames = FrameLoop::new(&ctx, 1, 4).expect("frame loop");
    let (slot, cmd, timestamps, _) = frames.begin(&ctx).expect("begin");
    exec.record(&cmd, slot, timestamps);
    frames.submit(&ctx, &[], &[]).expect("submit");
    // The fill may still be running: the buffer waits for the frame's fence.
    drop(target);
    assert_eq!(ctx.pending_releases(), 1, "destroyed while its frame ran");
    frames.finish(&ctx).expect("the frame finishes");
    assert_eq!(ctx.pending_releases(), 0, "kept after its frame completed");
}

#[test]
fn objects_dropped_after_their_frames_are_destroyed_by_finish() {
    let ctx = common::raw_context();
    let mut frames = FrameLoop::new(&ctx, 2, 1).expect("frame loop");
    let (_, _cmd, _, _) = frames.begin(&ctx).expect("begin");
    frames.submit(&ctx, &[], &[]).expect("submit");
    // Dropped with the frame (and the loop's own fences and pools) possibly in flight.
    drop(common::transfer_buffer(&ctx, "dropped in flight"));
    drop(frames);
    let report = ctx.finish();
    assert!(report.is_clean(), "{report}");
}

/// `Context::allocated_bytes` counts what is handed out and not yet freed: a 256-byte buffer
/// adds at least its 256 bytes (the allocation is the buffer's memory requirement, never less
/// than its size) and dropping it with nothing in flight gives them back exactly.
#[test]
fn allocated_bytes_follow_a_buffer_from_creation_to_drop() {
    let ctx = common::context();
    let before = ctx.allocated_bytes();
    let buffer = common::transfer_buffer(&ctx, "counted");
    let with = ctx.allocated_bytes();
    assert!(
        with >= before + 256,
        "{before} B before, {with} B with the buffer"
    );
    drop(buffer);
    assert_eq!(ctx.allocated_bytes(), before);
}

/// The soak benchmark's path (`voxgi bench soak`) on a short run of the moving scene: one
/// sample before the first frame, one every 10 frames and one after the last, each with an
/// RSS (on Linux) and the GPU memory the renderer holds; slopes are finite and the renderer
/// leaves no GPU memory behind once dropped. Not a memory assertion: 40 frames say nothing
/// about leaks; the benchmark's long runs do
/// (docs/measurements/long-runs.md).
#[test]
fn a_short_soak_run_reports_every_sample() {
    use voxgi::bench::{bench_soak, SoakBenchDesc};
    use voxgi::gi::GiMethod;
    let ctx = common::context();
    let scene = common::animated_scene();
    let desc = SoakBenchDesc {
        frames: 40,
        every: 10,
        methods: vec![GiMethod::None, GiMethod::Hemisphere],
        ..Default::default()
    };
    let mut seen = 0;
    let report = bench_soak(&ctx, &scene, "mover", &desc, &mut |_, _| seen += 1).expect("soak run");
    assert_eq!(report.rows.len(), 2);
    // Frames 0, 10, 20, 30 during the run and 40 after it, per method.
    assert_eq!(seen, 2 * 5);
    for row in &report.rows {
        let frames: Vec<usize> = row.samples.iter().map(|s| s.frame).collect();
        assert_eq!(frames, [0, 10, 20, 30, 40], "{:?}", row.method);
        for s in &row.samples {
            assert!(
                s.gpu_bytes > 0,
                "{:?}: the renderer holds GPU memory",
                row.method
            );
            if cfg!(target_os = "linux") {
                assert!(s.rss_bytes.is_some_and(|b| b > 0));
            }
        }
        assert!(row
            .gpu_slope_bytes_per_1000_frames
            .is_some_and(f64::is_finite));
        if cfg!(target_os = "linux") {
            assert!(row
                .rss_slope_bytes_per_1000_frames
                .is_some_and(f64::is_finite));
        }
        assert_eq!(row.gpu_bytes_after_drop, 0, "{:?}", row.method);
        assert!(row.wall_s.is_finite());
    }
    assert!(report.table().contains("hemisphere"));
}

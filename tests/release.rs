//! GPU objects release themselves when dropped (docs/ARCHITECTURE.md, "Errors, ownership,
//! tests"): with no submission in flight at once, otherwise once the frame that may use them
//! completed. The fixture's teardown check fails the test if an object was destroyed while a
//! command buffer still used it (the validation layers report that) or never freed.

mod common;

use voxgi::graph::{Access, GraphExecutor, RenderGraph};
use voxgi::vk::{vk, Buffer, BufferDesc, Context, FrameLoop, MemoryLocation};

fn host_buffer(ctx: &Context, name: &str) -> Buffer {
    ctx.create_buffer(&BufferDesc {
        name: name.into(),
        size_bytes: 256,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    })
    .expect("buffer")
}

#[test]
fn an_object_dropped_with_nothing_in_flight_is_destroyed_at_once() {
    let ctx = common::context();
    let buffer = host_buffer(&ctx, "idle");
    drop(buffer);
    assert_eq!(ctx.pending_releases(), 0);
}

#[test]
fn an_object_dropped_while_its_frame_is_in_flight_waits_for_the_frame() {
    let ctx = common::context();
    let target = host_buffer(&ctx, "in flight");
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
    drop(host_buffer(&ctx, "dropped in flight"));
    drop(frames);
    let report = ctx.finish();
    assert!(report.is_clean(), "{report}");
}

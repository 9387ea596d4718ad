//! Running a compiled graph headless: [`run_frames`] is the one frame driver of headless
//! renders, profiles, tests and benchmarks (the viewer's loop adds a swapchain); [`run_once`]
//! runs a graph a single time (one-time setup work: atlases, static voxelization; read-backs
//! in tests).

use super::{Access, BufferHandle, GraphError, GraphExecutor, ImageHandle, RenderGraph};
use crate::vk::{vk, Buffer, BufferDesc, Context, FrameLoop, MemoryLocation, PassTiming, VkError};

/// Errors of [`run_once`]: compiling the graph, or running it on the GPU.
#[derive(Debug, thiserror::Error)]
pub enum OneShotError {
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error(transparent)]
    Vk(#[from] VkError),
}

/// Runs a graph once, waits, and returns the timings of its passes.
pub fn run_once(ctx: &Context, graph: RenderGraph) -> Result<Vec<PassTiming>, OneShotError> {
    let exec = GraphExecutor::new(ctx, graph, 1)?;
    let mut frames = FrameLoop::new(ctx, 1, exec.compiled().order.len() as u32)?;
    let (slot, cmd, ts, _) = frames.begin(ctx)?;
    exec.record(&cmd, slot, ts);
    let submitted = frames.submit(ctx, &[], &[]);
    let finished = frames.finish(ctx);
    submitted?;
    Ok(finished?.into_iter().last().unwrap_or_default())
}

/// Runs `frames` frames of `exec` with `MAX_FRAMES_IN_FLIGHT` slots. Before recording each
/// frame, after its slot's fence, `write(slot)` writes the slot's host data (frame
/// constants). Returns the per-pass timings of every finished frame whose index is at least
/// `keep_from` (frames without timings are skipped), and waits for the GPU before returning.
pub fn run_frames(
    ctx: &Context,
    exec: &GraphExecutor,
    frames: usize,
    keep_from: usize,
    mut write: impl FnMut(usize),
) -> Result<Vec<Vec<PassTiming>>, VkError> {
    let in_flight = crate::vk::MAX_FRAMES_IN_FLIGHT;
    let mut frame_loop = FrameLoop::new(ctx, in_flight, exec.compiled().order.len() as u32)?;
    let mut kept = Vec::new();
    let run = (|| -> Result<(), VkError> {
        for i in 0..frames {
            let slot = frame_loop.current_slot();
            // begin() waits for the slot's fence, so the host may rewrite its data after it;
            // the timings it returns are those of frame i - in_flight.
            let (_, cmd, ts, done) = frame_loop.begin(ctx)?;
            if i >= keep_from + in_flight && !done.is_empty() {
                kept.push(done);
            }
            write(slot);
            exec.record(&cmd, slot, ts);
            frame_loop.submit(ctx, &[], &[])?;
        }
        Ok(())
    })();
    let finished = frame_loop.finish(ctx);
    let _ = ctx.wait_idle();
    run?;
    let finished = finished?;
    // The last `in_flight` frames finish here, oldest first.
    let first_finished = frames.saturating_sub(finished.len());
    kept.extend(
        finished
            .into_iter()
            .enumerate()
            .filter(|(k, t)| first_finished + k >= keep_from && !t.is_empty())
            .map(|(_, t)| t),
    );
    Ok(kept)
}

/// A host-visible buffer for reading back GPU data.
pub fn readback_buffer(ctx: &Context, name: &str, size_bytes: u64) -> Result<Buffer, VkError> {
    ctx.create_buffer(&BufferDesc {
        name: name.into(),
        size_bytes,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    })
}

/// Declares pass `name` copying mip 0, layer 0 of `image` into `buffer` (tightly packed rows)
/// for the host to read after the frame.
pub fn add_readback(g: &mut RenderGraph, name: &str, image: ImageHandle, buffer: BufferHandle) {
    g.add_pass(name)
        .read(image, Access::TransferRead)
        .write(buffer, Access::TransferWrite)
        .record(move |ctx| {
            let img = ctx.image(image);
            let extent = vk::Extent3D {
                width: img.desc.width,
                height: img.desc.height,
                depth: 1,
            };
            ctx.cmd
                .copy_image_to_buffer(img.raw, extent, 0, 1, ctx.buffer(buffer).raw);
        });
}

//! Running a graph once, outside a frame loop: one-time setup work (atlases, static
//! voxelization), read-backs in tests, and benchmarks.

use super::{GraphError, GraphExecutor, RenderGraph};
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
    let result = (|| -> Result<Vec<PassTiming>, VkError> {
        let mut frames = FrameLoop::new(ctx, 1, exec.compiled().order.len() as u32)?;
        let run = (|| -> Result<(), VkError> {
            let (slot, cmd, ts, _) = frames.begin(ctx)?;
            exec.record(&cmd, slot, ts);
            frames.submit(ctx, &[], &[])
        })();
        let finished = frames.finish(ctx);
        frames.destroy(ctx);
        run?;
        Ok(finished?.into_iter().last().unwrap_or_default())
    })();
    let _ = ctx.wait_idle();
    exec.destroy(ctx);
    Ok(result?)
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

//! `oit_clear`: empties the transparency lists at the start of a frame — every head pointer
//! ~0 and the node counter 0, with the node buffer's capacity (`glsl/oit_clear.comp`).

use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{ComputePipeline, Context, PushLayout, VkError};

/// Push constants of `oit_clear.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuOitClearPush {
    /// Nodes the node buffer holds.
    pub capacity: u32,
}

crate::push_constants!(GpuOitClearPush { capacity });

pub struct OitClearPass {
    pipeline: ComputePipeline,
}

impl OitClearPass {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let pipeline =
            ctx.compute_pipeline("oit_clear.comp", PushLayout::of::<GpuOitClearPush>(), &[])?;
        Ok(Self { pipeline })
    }

    /// Declares the pass writing `heads` (r32ui, the frame's size) and `counters`.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        heads: ImageHandle,
        counters: BufferHandle,
        capacity: u32,
        (w, h): (u32, u32),
    ) {
        let pipe = *self.pipeline;
        let push = GpuOitClearPush { capacity };
        g.add_pass("oit_clear")
            .pipeline(&pipe)
            .bind(0, heads, Access::StorageWrite(Shader::Compute))
            .bind(1, counters, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
    }
}

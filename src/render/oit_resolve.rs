//! `oit_resolve`: sorts each pixel's transparency list (its [`MAX_LAYERS`] nearest layers)
//! and blends it back to front over the lit opaque radiance (`glsl/oit_resolve.comp`).

use super::HDR;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// Layers blended per pixel (K): a pixel's nearer layers win; more are dropped and counted.
/// 16 layers of d = 0.5 leave 2⁻¹⁶ of what is behind them, below 8-bit display precision.
pub const MAX_LAYERS: u32 = 16;

pub struct OitResolvePass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
}

impl OitResolvePass {
    /// `sampler`: the nearest-neighbour sampler the opaque radiance is read with.
    pub fn new(ctx: &Context, sampler: vk::Sampler) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "oit_resolve.comp",
            None,
            &crate::spec_constants![K = MAX_LAYERS],
        )?;
        Ok(Self { pipeline, sampler })
    }

    /// Declares the pass; returns the blended radiance (RGBA32F). `frame`: the frame
    /// constants, whose pre-exposure scales the half-float layers back.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        (heads, nodes, counters): (ImageHandle, BufferHandle, BufferHandle),
        frame: BufferHandle,
        opaque: ImageHandle,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let radiance = g.create_image(ImageDesc::new_2d("radiance with transparency", HDR, w, h));
        let pipe = *self.pipeline;
        let c = Shader::Compute;
        g.add_pass("oit_resolve")
            .pipeline(&pipe)
            .bind(0, heads, Access::StorageRead(c))
            .bind(1, nodes, Access::StorageRead(c))
            .bind(2, counters, Access::StorageReadWrite(c))
            .bind_sampled(3, opaque, self.sampler, c)
            .bind(4, radiance, Access::StorageWrite(c))
            .bind(5, frame, Access::StorageRead(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        radiance
    }
}

//! `tonemap`: linear HDR radiance to sRGB-encoded RGBA8 with the chosen operator
//! (`glsl/tonemap.comp`; the operators are in [`ToneOperator`](super::ToneOperator)).

use super::ToneMap;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// Push constants of `tonemap.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTonemapPush {
    pub exposure: f32,
    /// [`ToneOperator::shader_id`](super::ToneOperator::shader_id).
    pub op: u32,
    pub white: f32,
    pub drago_bias: f32,
}

crate::push_constants!(GpuTonemapPush {
    exposure,
    op,
    white,
    drago_bias
});

impl From<ToneMap> for GpuTonemapPush {
    fn from(tm: ToneMap) -> Self {
        Self {
            exposure: tm.exposure,
            op: tm.operator.shader_id(),
            white: tm.white,
            drago_bias: tm.drago_bias,
        }
    }
}

pub struct TonemapPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
}

impl TonemapPass {
    /// `sampler`: how the radiance is read (nearest: one texel per pixel).
    pub fn new(ctx: &Context, sampler: vk::Sampler) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "tonemap.comp",
            crate::vk::PushLayout::of::<GpuTonemapPush>(),
            &[],
        )?;
        Ok(Self { pipeline, sampler })
    }

    /// Declares the pass; returns the tone-mapped image (RGBA8 UNORM holding sRGB values).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        radiance: ImageHandle,
        tone_map: ToneMap,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let ldr = g.create_image(ImageDesc::new_2d("ldr", vk::Format::R8G8B8A8_UNORM, w, h));
        let pipe = *self.pipeline;
        let push = GpuTonemapPush::from(tone_map);
        g.add_pass("tonemap")
            .pipeline(&pipe)
            .bind_sampled(0, radiance, self.sampler, Shader::Compute)
            .bind(1, ldr, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        ldr
    }
}

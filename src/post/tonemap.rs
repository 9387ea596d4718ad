//! `tonemap`: linear HDR radiance to sRGB-encoded RGBA8 with the chosen operator
//! (`glsl/tonemap.comp`; the operators are in [`ToneOperator`](super::ToneOperator)), times an
//! exposure from a buffer (auto exposure's, or a fixed 1), optionally dithered.

use super::exposure::EXPOSURE_STATE;
use super::ToneMap;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Buffer, ComputePipeline, Context, ImageDesc, VkError};

/// Push constants of `tonemap.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTonemapPush {
    pub exposure: f32,
    /// [`ToneOperator::shader_id`](super::ToneOperator::shader_id).
    pub op: u32,
    pub white: f32,
    pub drago_bias: f32,
    /// 1: triangular dither of ±1/255 before 8-bit quantization.
    pub dither: u32,
}

crate::push_constants!(GpuTonemapPush {
    exposure,
    op,
    white,
    drago_bias,
    dither
});

impl From<ToneMap> for GpuTonemapPush {
    fn from(tm: ToneMap) -> Self {
        Self {
            exposure: tm.exposure,
            op: tm.operator.shader_id(),
            white: tm.white,
            drago_bias: tm.drago_bias,
            dither: u32::from(tm.dither),
        }
    }
}

pub struct TonemapPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
    /// The exposure buffer without auto exposure: holds 1.
    unit_exposure: Buffer,
}

impl TonemapPass {
    /// `sampler`: how the radiance is read (nearest: one texel per pixel).
    pub fn new(ctx: &Context, sampler: vk::Sampler) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "tonemap.comp",
            crate::vk::PushLayout::of::<GpuTonemapPush>(),
            &[],
        )?;
        let unit_exposure = ctx.upload_buffer(
            "unit exposure",
            bytemuck::bytes_of(&[1.0f32, 0.0]),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Self {
            pipeline,
            sampler,
            unit_exposure,
        })
    }

    /// Declares the pass; returns the tone-mapped image (RGBA8 UNORM holding sRGB values).
    /// `exposure`: auto exposure's buffer ([`super::ExposurePass::declare`]), else 1.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        radiance: ImageHandle,
        exposure: Option<BufferHandle>,
        tone_map: ToneMap,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let ldr = g.create_image(ImageDesc::new_2d("ldr", vk::Format::R8G8B8A8_UNORM, w, h));
        let exposure =
            exposure.unwrap_or_else(|| g.import_buffer(&self.unit_exposure, EXPOSURE_STATE));
        let pipe = *self.pipeline;
        let push = GpuTonemapPush::from(tone_map);
        g.add_pass("tonemap")
            .pipeline(&pipe)
            .bind_sampled(0, radiance, self.sampler, Shader::Compute)
            .bind(1, ldr, Access::StorageWrite(Shader::Compute))
            .bind(2, exposure, Access::StorageRead(Shader::Compute))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        ldr
    }
}

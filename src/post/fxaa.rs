//! `fxaa`: fast approximate anti-aliasing of the tone-mapped image (`glsl/fxaa.comp`; FXAA
//! 3.11 quality, Lottes 2011; Oetke 2017 §4.4). Flat regions pass unchanged; at an edge the
//! search along it sets each pixel's blend across it from its position along the step.

use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, Sampler, VkError};

pub struct FxaaPass {
    pipeline: ComputePipeline,
    /// Bilinear: the shader's taps between texels.
    sampler: Sampler,
}

impl FxaaPass {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline("fxaa.comp", None, &[])?;
        let sampler = ctx.create_sampler(vk::Filter::LINEAR, false)?;
        Ok(Self { pipeline, sampler })
    }

    /// Declares the pass over `ldr` (RGBA8 sRGB values); returns the anti-aliased image.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        ldr: ImageHandle,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let out = g.create_image(ImageDesc::new_2d("fxaa", vk::Format::R8G8B8A8_UNORM, w, h));
        let pipe = *self.pipeline;
        g.add_pass("fxaa")
            .pipeline(&pipe)
            .bind_sampled(0, ldr, self.sampler.raw, Shader::Compute)
            .bind(1, out, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        out
    }
}

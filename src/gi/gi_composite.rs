//! `gi_composite`: the frame's radiance, direct plus indirect (Lambert pixels: albedo / π
//! times the filtered irradiance; Phong and GGX pixels: their indirect radiance as stored), the
//! indirect term multiplied by the SAO term when there is one (Oetke 2017 §2.5).

use super::GiInputs;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// The composite's pipeline.
pub struct GiComposite {
    pipeline: ComputePipeline,
}

impl GiComposite {
    /// `has_phong`: the G-buffer has a specular image (specialization constant 0); `sao`:
    /// an AO term multiplies the indirect light (constant 1), `sao_view`: the composite
    /// writes the AO term instead (constant 2); `ggx_radiance`: the indirect image holds GGX
    /// pixels' radiance, not their irradiance (every method in scenes with GGX materials:
    /// each shades GGX receivers with their whole BRDF; constant 3).
    pub fn new(
        ctx: &Context,
        has_phong: bool,
        (sao, sao_view): (bool, bool),
        ggx_radiance: bool,
    ) -> Result<Self, VkError> {
        let spec = crate::spec_constants![
            HAS_PHONG = has_phong,
            HAS_SAO = sao,
            SAO_VIEW = sao && sao_view,
            GGX_RADIANCE = ggx_radiance,
        ];
        let pipeline = ctx.compute_pipeline("gi_composite.comp", None, &spec)?;
        Ok(Self { pipeline })
    }

    /// Declares the composite of `i.direct` and `indirect` (times `ao`, the SAO term at the
    /// frame's size, when given); returns the total radiance.
    pub fn add_pass(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        indirect: ImageHandle,
        ao: Option<ImageHandle>,
    ) -> ImageHandle {
        let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
        let total = g.create_image(ImageDesc::new_2d(
            "radiance (direct + indirect)",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        let pipe = *self.pipeline;
        let c = Shader::Compute;
        // Without Phong materials the shader never reads its specular binding; albedo fills it.
        let specular = i.specular.unwrap_or(i.albedo);
        // Likewise its SAO binding without SAO.
        let ao = ao.unwrap_or(i.albedo);
        g.add_pass("gi_composite")
            .pipeline(&pipe)
            .bind_sampled(0, i.direct, sampler, c)
            .bind_sampled(1, i.albedo, sampler, c)
            .bind_sampled(2, indirect, sampler, c)
            .bind(3, total, Access::StorageWrite(c))
            .bind_sampled(4, specular, sampler, c)
            .bind_sampled(5, ao, sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        total
    }
}

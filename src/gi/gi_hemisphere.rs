//! `gi_hemisphere`: one bounce by hemisphere sampling, radiance at the hits read from the
//! reflective light maps (Thiedemann 2010 §6.4.1).

use super::gi_common::{add_ray_pass, GiShared, GpuGiPush};
use super::{GiInputs, GiMethodPasses, GiOutput};
use crate::graph::{Access, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};

/// The hemisphere pass reading the light maps.
pub struct GiHemisphere {
    pipeline: ComputePipeline,
}

impl GiHemisphere {
    /// `has_phong`: the G-buffer has a specular image (specialization constant 0).
    pub fn new(ctx: &Context, has_phong: bool) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "gi_hemisphere.comp",
            PushLayout::of::<GpuGiPush>(),
            &[(0, u32::from(has_phong))],
        )?;
        Ok(Self { pipeline })
    }
}

impl GiMethodPasses for GiHemisphere {
    fn add_passes(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> GiOutput {
        let irradiance = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        let push = shared.push;
        add_ray_pass(
            g,
            "gi_hemisphere",
            self.pipeline,
            i,
            shared,
            &[(5, i.rlm_radiance), (6, i.rlm_position), (7, i.rlm_normal)],
            (irradiance, Access::StorageWrite(Shader::Compute)),
            Some(i.materials),
            move || push,
        );
        irradiance.into()
    }

    fn destroy(self: Box<Self>, ctx: &Context) {
        ctx.destroy_compute_pipeline(self.pipeline);
    }
}

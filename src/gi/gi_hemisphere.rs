//! `gi_hemisphere` and `gi_hemisphere_emission`: one bounce by hemisphere sampling, radiance at
//! the hits read from the reflective light maps (Thiedemann 2010 §6.4.1). In scenes with
//! emitters the second variant also adds, at a hit on an emitter's front side, its emitted
//! radiance from the emission volume (the light maps see only what the lights see), as the
//! path tracer does.

use super::gi_common::{add_ray_pass, GiShared, GpuGiPush};
use super::{GiInputs, GiMethodPasses, GiOutput};
use crate::graph::{Access, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};

/// The hemisphere pass reading the light maps (and, with emitters, the emission volume).
pub struct GiHemisphere {
    pipeline: ComputePipeline,
    /// The pass reads the emission and normal volumes (`gi_hemisphere_emission`).
    emission: bool,
}

impl GiHemisphere {
    /// `has_phong`: the G-buffer has a specular image (specialization constant 0).
    /// `has_ggx`: some material is GGX, whose light-map senders get their whole BRDF toward
    /// the ray (specialization constant 1). `emission`: the scene has emitters; the assembly
    /// then writes the attribute volumes ([`super::GiPasses::needs_attribute_volumes`]).
    /// `environment`: `Environment::shader_kind`, what rays leaving the grid read.
    /// `advance`: the ray pattern advances every frame (temporal accumulation).
    pub fn new(
        ctx: &Context,
        (has_phong, has_ggx): (bool, bool),
        emission: bool,
        environment: u32,
        advance: bool,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            if emission {
                "gi_hemisphere_emission.comp"
            } else {
                "gi_hemisphere.comp"
            },
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                HAS_PHONG = has_phong,
                HAS_GGX = has_ggx,
                ENVIRONMENT = environment,
                ADVANCE = advance,
            ],
        )?;
        Ok(Self { pipeline, emission })
    }

    /// The pass's (and its shader's) name.
    fn name(emission: bool) -> &'static str {
        if emission {
            "gi_hemisphere_emission"
        } else {
            "gi_hemisphere"
        }
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
        let seed = shared.seed();
        let mut own = vec![(5, i.rlm_radiance), (6, i.rlm_position), (7, i.rlm_normal)];
        if self.emission {
            // The assembly writes the volumes (with an emission volume) in scenes with emitters.
            if let Some(v) = shared.attributes {
                own.push((12, v.emission.unwrap_or(v.albedo)));
                own.push((13, v.normal));
            }
        }
        add_ray_pass(
            g,
            Self::name(self.emission),
            *self.pipeline,
            i,
            shared,
            &own,
            (irradiance, Access::StorageWrite(Shader::Compute)),
            &[(11, i.materials), (14, i.materials_pbr)],
            move || GpuGiPush {
                seed: seed(),
                ..push
            },
        );
        irradiance.into()
    }
}

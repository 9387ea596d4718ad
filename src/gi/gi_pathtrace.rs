//! `gi_pathtrace`: B bounces through the voxels with albedo and normal from the attribute
//! volumes and direct light at every hit from the shadow maps, accumulated over frames into a
//! history image (Thiedemann 2010 §6.4.2). In scenes with emitters, a hit on an emitter's front
//! side adds its emitted radiance from the emission volume (a specialization constant: no
//! emission reads otherwise). With a material volume (Phong or GGX materials,
//! `GiSettings::pathtrace_lobes`) every bounce samples its surface's lobe, not only the first
//! (another specialization constant: later bounces are Lambert otherwise). With
//! `GiSettings::emitter_sampling`, in scenes with emissive triangles, every path vertex also
//! samples one of them by power (next-event estimation, [`super::emitters`]) and weighs it and
//! the BSDF ray's emitter hit by multiple importance sampling (a third specialization
//! constant and the emitter list's buffer at binding 14). With `GiSettings::env_sampling`, in
//! scenes with an environment map, every path vertex also draws a direction from the map's
//! luminance (its tables at binding 16), weighed against the BSDF ray by the balance heuristic.

use super::emitters::EmitterBuffer;
use super::gi_common::{add_ray_pass, GiShared, GpuGiPush};
use super::{GiInputs, GiMethodPasses, GiOutput, GiTarget, MethodWorld};
use crate::graph::{Access, RenderGraph, Shader};
use crate::scene::Environment;
use crate::vk::{vk, ComputePipeline, Context, Image, ImageDesc, PushLayout, VkError};
use std::sync::atomic::Ordering;

/// The path tracer's pipeline and its accumulation history (the frame's size, rgba32f), one
/// per stereo eye of a one-pass stereo frame.
pub struct GiPathtrace {
    pipeline: ComputePipeline,
    /// Empty under temporal accumulation (`gi_temporal` keeps the history; the pass writes
    /// each frame's estimate to an image of the frame).
    histories: Vec<Image>,
    /// The emissive triangles next-event estimation samples (scenes with them, with
    /// `GiSettings::emitter_sampling`).
    emitters: Option<EmitterBuffer>,
}

impl GiPathtrace {
    /// The accumulation history of a `w`×`h` frame.
    pub fn history_desc((w, h): (u32, u32)) -> ImageDesc {
        ImageDesc::new_2d("path tracer history", vk::Format::R32G32B32A32_SFLOAT, w, h)
            .with_usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED)
    }

    /// `lobes`: later bounces read the material volume (the assembly creates it then).
    /// `emitter_sampling`: next-event estimation toward the emissive triangles, if any.
    /// `env_sampling`: next-event estimation toward the environment map, if the scene has one.
    /// `temporal`: `gi_temporal` accumulates; the pass keeps no history of its own.
    pub fn new(
        ctx: &Context,
        target: &GiTarget<'_>,
        lobes: bool,
        emitter_sampling: bool,
        env_sampling: bool,
        temporal: bool,
    ) -> Result<Self, VkError> {
        let (w, h) = target.size;
        let emitters = match emitter_sampling && target.scene.has_emission() {
            true => EmitterBuffer::new(ctx, target.scene, target.time_s)?,
            false => None,
        };
        let environment = Environment::shader_kind(target.scene.environment.as_ref());
        let pipeline = ctx.compute_pipeline(
            "gi_pathtrace.comp",
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                // The lobe target exists with Phong or GGX materials; both sample it.
                HAS_PHONG = target.has_phong || target.scene.has_ggx(),
                HAS_EMISSION = target.scene.has_emission(),
                HAS_MATERIAL_VOLUME = lobes && !target.scene.is_all_lambert(),
                HAS_EMITTERS = emitters.is_some(),
                ENVIRONMENT = environment,
                ACCUMULATE = !temporal,
                ENV_SAMPLING = env_sampling && environment == 2,
            ],
        )?;
        let eyes = if temporal { 0 } else { target.eyes.max(1) };
        let histories = (0..eyes)
            .map(|_| {
                ctx.create_zeroed_image(
                    &Self::history_desc((w, h)),
                    Access::Sampled(Shader::Compute).info().layout,
                )
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            pipeline,
            histories,
            emitters,
        })
    }
}

impl GiMethodPasses for GiPathtrace {
    fn add_world_passes(&self, g: &mut RenderGraph, _i: &GiInputs, _s: &GiShared) -> MethodWorld {
        MethodWorld {
            image: None,
            buffer: self.emitters.as_ref().map(|e| e.import(g)),
        }
    }

    fn add_passes(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> GiOutput {
        // One history per eye; `GiTarget::eyes` made as many as the assembly declares. Under
        // temporal accumulation, this frame's estimate.
        let (history, out_access) = match self.histories.len() {
            0 => (
                g.create_image(ImageDesc::new_2d(
                    "path tracer estimate",
                    vk::Format::R32G32B32A32_SFLOAT,
                    i.width,
                    i.height,
                )),
                Access::StorageWrite(Shader::Compute),
            ),
            n => {
                let own = &self.histories[(shared.eye as usize).min(n - 1)];
                (
                    g.import_image(own, Access::Sampled(Shader::Compute)),
                    Access::StorageReadWrite(Shader::Compute),
                )
            }
        };
        // The assembly writes the volumes for the methods that need them (this one does).
        let Some(v) = shared.attributes else {
            return history.into();
        };
        // Without emitters the shader never reads its emission binding; albedo fills it.
        let emission = v.emission.unwrap_or(v.albedo);
        // Without a material volume the shader never reads its binding either.
        let material = v.material.unwrap_or(v.albedo);
        // The emitter list, imported once per frame (`add_world_passes`, shared by both
        // stereo eyes); without emitter sampling the shader never reads its binding and the
        // ray-mask table fills it.
        let emitters = shared.world.buffer.unwrap_or(shared.lut);
        // The map's tables, read only with `gi.env_sampling` in a scene with a map.
        let environment_cdf = i.environment_cdf.unwrap_or(shared.lut);
        let push = shared.push;
        let frames = shared.frames.clone();
        let temporal_seed = shared.sample_index.is_some().then(|| shared.seed());
        add_ray_pass(
            g,
            "gi_pathtrace",
            *self.pipeline,
            i,
            shared,
            &[
                (5, v.albedo),
                (6, v.normal),
                (7, i.shadow_map),
                (12, emission),
                (13, material),
            ],
            (history, out_access),
            &[(14, emitters), (16, environment_cdf)],
            move || GpuGiPush {
                seed: match &temporal_seed {
                    Some(seed) => seed(),
                    // Frames accumulated before this one (`GiPasses::advance` ran before
                    // recording).
                    None => frames.load(Ordering::SeqCst).saturating_sub(1),
                },
                ..push
            },
        );
        history.into()
    }

    fn update_scene(&mut self, scene: &crate::scene::Scene, t_s: f32) {
        if let Some(e) = &mut self.emitters {
            e.update(scene, t_s);
        }
    }

    fn write_slot(&mut self, slot: usize) {
        if let Some(e) = &mut self.emitters {
            e.write_slot(slot);
        }
    }
}

//! `gi_radiance_volume` and `gi_hemisphere_volume`: hemisphere sampling (Thiedemann 2010
//! §6.4.1) that reads the radiance leaving a hit from a direct-radiance voxel volume (§6.3.2)
//! instead of the light maps. The first pass fills the volume from the attribute volumes and the shadow
//! maps, the second samples the hemisphere against it. With Phong or GGX materials the volume
//! holds a glossy voxel's diffuse part and its lights' visibility, and the second pass adds
//! its specular lobe toward each ray from the material volume and the lights
//! (docs/design/materials.md). With `GiSettings::emitter_sampling`, in scenes with emissive
//! triangles, the volume pass also samples the emitter list (binding 14, next-event
//! estimation as in the path tracer, [`super::emitters`]) for the light the emitters put on
//! each voxel.

use super::emitters::EmitterBuffer;
use super::gi_common::{add_ray_pass, GiShared, GpuGiPush};
use super::{GiInputs, GiMethodPasses, GiOutput, GiTarget, MethodWorld};
use crate::graph::{Access, Cache, ImageHandle, RenderGraph, Shader};
use crate::scene::Environment;
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use std::sync::Arc;

/// The direct-radiance volume's passes. The volume (rgba32f, congruent with the bits) is the
/// graph's: a cached image kept while the lights and the objects stay (`shadow.cache`), else a
/// transient computed every frame. f32 because f16 cannot hold radiance from lights of 1e-6 to
/// 1e6 W/sr (tests/extremes.rs): 16 bytes per voxel, 33.5 MB at 128³.
pub struct GiRadianceVolume {
    volume_pipeline: ComputePipeline,
    hemisphere_pipeline: ComputePipeline,
    volume: ImageDesc,
    /// The volume's validity with `shadow.cache` ([`GiMethodPasses::world_cache`]).
    cache: Option<Arc<Cache>>,
    /// The emissive triangles' table (`emitter_sampling` in a scene with emitters).
    emitters: Option<EmitterBuffer>,
}

impl GiRadianceVolume {
    /// `emitter_sampling`: the volume pass samples the emissive triangles, if any.
    pub fn new(
        ctx: &Context,
        target: &GiTarget<'_>,
        emitter_sampling: bool,
    ) -> Result<Self, VkError> {
        let emitters = match emitter_sampling && target.scene.has_emission() {
            true => EmitterBuffer::new(ctx, target.scene, target.time_s)?,
            false => None,
        };
        let volume_pipeline = ctx.compute_pipeline(
            "gi_radiance_volume.comp",
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                HAS_EMISSION = target.scene.has_emission(),
                HAS_LOBES = !target.scene.is_all_lambert(),
                HAS_EMITTERS = emitters.is_some(),
            ],
        )?;
        let hemisphere_pipeline = ctx.compute_pipeline(
            "gi_hemisphere_volume.comp",
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                HAS_PHONG = target.has_phong,
                HAS_GGX = target.scene.has_ggx(),
                HAS_EMISSION = target.scene.has_emission(),
                ENVIRONMENT = Environment::shader_kind(target.scene.environment.as_ref()),
                ADVANCE = target.temporal,
            ],
        )?;
        let ext = target.grid.extent_voxels();
        let volume = ImageDesc::new_2d(
            "direct radiance volume",
            vk::Format::R32G32B32A32_SFLOAT,
            ext.x,
            ext.y,
        )
        .with_depth(ext.z);
        Ok(Self {
            volume_pipeline,
            hemisphere_pipeline,
            volume,
            cache: target.cache.then(|| Cache::new("direct radiance volume")),
            emitters,
        })
    }
}

impl GiRadianceVolume {
    /// The volume: a cached image of the graph's with the cache on, else a transient.
    fn declare_volume(&self, g: &mut RenderGraph) -> ImageHandle {
        match &self.cache {
            Some(cache) => g.create_cached_image(
                self.volume.clone(),
                Access::Sampled(Shader::Compute),
                std::slice::from_ref(cache),
            ),
            None => g.create_image(self.volume.clone()),
        }
    }
}

impl GiMethodPasses for GiRadianceVolume {
    fn world_cache(&self) -> Option<&Arc<Cache>> {
        self.cache.as_ref()
    }

    /// The volume pass: view-independent, so a stereo frame's eyes share the volume.
    fn add_world_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        shared: &GiShared,
    ) -> MethodWorld {
        let c = Shader::Compute;
        let volume = self.declare_volume(g);
        let world = MethodWorld {
            image: Some(volume),
            buffer: None,
        };
        // The assembly writes the volumes for the methods that need them (this one does).
        let Some(v) = shared.attributes else {
            return world;
        };
        let (albedo, normal) = (v.albedo, v.normal);
        // Without emitters the shader never reads its emission binding, nor without Phong or
        // GGX materials its material binding; albedo fills them.
        let emission = v.emission.unwrap_or(albedo);
        let material = v.material.unwrap_or(albedo);
        // The emitter list; without it the shader never reads its binding (nor the ray-mask
        // table's), and the ray-mask table fills it.
        let emitters = self.emitters.as_ref().map_or(shared.lut, |e| e.import(g));
        let pipe = *self.volume_pipeline;
        let push = shared.push;
        let dims = push.dims;
        let sampler = shared.sampler;
        // The direct radiance changes only with the lights, the shadow maps (which the lights
        // and the objects decide) and the scene: with the cache on, the pass runs in the first
        // frame and after such a change (`GiPasses::lights_changed`, `objects_moved`), not when
        // only the camera moves. It cost 675 ms per frame at 128³ on lavapipe.
        g.add_pass("gi_radiance_volume")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.voxels, sampler, c)
            .bind_sampled(2, albedo, sampler, c)
            .bind_sampled(3, normal, sampler, c)
            .bind_sampled(4, i.shadow_map, sampler, c)
            .bind(5, volume, Access::StorageWrite(c))
            .bind_sampled(6, emission, sampler, c)
            .bind_sampled(7, material, sampler, c)
            .bind(8, shared.lut, Access::StorageRead(c))
            .bind(14, emitters, Access::StorageRead(c))
            .cached(self.cache.as_ref())
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(
                    (dims[0] as u32).div_ceil(4),
                    (dims[1] as u32).div_ceil(4),
                    (dims[2] as u32).div_ceil(4),
                );
            });
        world
    }

    fn add_passes(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> GiOutput {
        let c = Shader::Compute;
        // `add_world_passes` imported the volume (`GiPasses::add_eye_passes` runs it first).
        let volume = match shared.world.image {
            Some(volume) => volume,
            None => self.declare_volume(g),
        };
        let Some(v) = shared.attributes else {
            return volume.into();
        };
        let normal = v.normal;
        // A glossy hit's specular lobe (Phong or GGX materials) reads the material, base color
        // and emission volumes; otherwise albedo fills the material and emission bindings.
        let material = v.material.unwrap_or(v.albedo);
        let emission = v.emission.unwrap_or(v.albedo);
        let push = shared.push;
        let seed = shared.seed();
        let irradiance = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        add_ray_pass(
            g,
            "gi_hemisphere_volume",
            *self.hemisphere_pipeline,
            i,
            shared,
            &[
                (5, volume),
                (6, normal),
                (7, material),
                (11, v.albedo),
                (13, emission),
            ],
            (irradiance, Access::StorageWrite(c)),
            &[],
            move || GpuGiPush {
                seed: seed(),
                ..push
            },
        );
        irradiance.into()
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

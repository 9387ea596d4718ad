//! `deferred_direct`: direct light of every light at every G-buffer pixel, with shadow-map
//! visibility (`glsl/deferred_direct.comp`).

use super::gbuffer::Gbuffer;
use super::scene_gpu::SceneInputs;
use super::HDR;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

pub struct DeferredDirectPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
}

impl DeferredDirectPass {
    /// `sampler`: the nearest-neighbour sampler the G-buffer and shadow maps are read with.
    /// `phong`, `ggx`, `emission`: which material models the scene has (the shader compiles in
    /// only those); `environment`: `Environment::shader_kind`, what the background shows.
    pub fn new(
        ctx: &Context,
        (phong, ggx, emission): (bool, bool, bool),
        environment: u32,
        sampler: vk::Sampler,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "deferred_direct.comp",
            None,
            &crate::spec_constants![
                HAS_PHONG = phong,
                HAS_GGX = ggx,
                HAS_EMISSION = emission,
                ENVIRONMENT = environment,
            ],
        )?;
        Ok(Self { pipeline, sampler })
    }

    /// Declares the pass; returns the linear radiance it writes (RGBA32F).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        shadow_maps: ImageHandle,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let radiance = g.create_image(ImageDesc::new_2d("radiance", HDR, w, h));
        let pipe = *self.pipeline;
        let (s, c) = (self.sampler, Shader::Compute);
        // Without Phong/GGX materials or emitters the shader never reads those bindings;
        // albedo fills them.
        let specular = gbuffer.specular.unwrap_or(gbuffer.albedo);
        let emission = gbuffer.emission.unwrap_or(gbuffer.albedo);
        let environment = scene.environment_map.unwrap_or(gbuffer.albedo);
        g.add_pass("deferred_direct")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(c))
            .bind_sampled(1, gbuffer.albedo, s, c)
            .bind_sampled(2, gbuffer.normal, s, c)
            .bind_sampled(3, specular, s, c)
            .bind_sampled(4, gbuffer.depth, s, c)
            .bind_sampled(5, shadow_maps, s, c)
            .bind(6, radiance, Access::StorageWrite(c))
            .bind_sampled(7, emission, s, c)
            .bind_sampled(8, environment, scene.environment_sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        radiance
    }
}

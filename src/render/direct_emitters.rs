//! `direct_emitters`: the direct light of the emissive triangles and of the environment at
//! every G-buffer pixel, with voxel visibility, added to `deferred_direct`'s radiance
//! (`glsl/direct_emitters.comp`; docs/design/emitter-sampling.md, "Direct light").
//!
//! It runs only where no GI method brings that light already, so nothing is counted twice:
//!
//! - the emitters under `--gi none` (the voxel methods reach them through their first bounce,
//!   and screen-space GI gathers the on-screen emission from the direct image);
//! - the environment under `--gi none`, `--gi ssgi` and `--gi vpl` (screen-space GI has no
//!   ray that can leave the scene, and the VPLs start at lights only, so neither reads the
//!   environment; the hemisphere rays and the path tracer bring its first bounce themselves).
//!
//! These are facts about the methods that their specs (`gi::method`) do not state yet; the
//! match below is the one place that holds them.
//!
//! The emitter list is the path tracer's ([`crate::gi::emitters`]); the rays are the GI rays'
//! voxel traversal with the GI settings' offsets and length ([`GpuGiPush`]), their count per
//! pixel `shadow.direct_samples` (in the push constants' `rays`).

use super::gbuffer::Gbuffer;
use super::scene_gpu::SceneInputs;
use super::HDR;
use crate::gi::emitters::EmitterBuffer;
use crate::gi::gi_common::GpuGiPush;
use crate::gi::{GiMethod, GiTarget};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::{Environment, Scene};
use crate::vk::{vk, Buffer, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use crate::voxel::ray_mask::RayMaskLut;

/// Which light the pass samples for `method` in `scene`: (the emitters, the environment);
/// `None` when neither (then the pass, and for it the voxel grid, is not made).
pub fn sampled_light(method: GiMethod, scene: &Scene) -> Option<(bool, bool)> {
    let emitters = method == GiMethod::None && scene.has_emission();
    let environment = matches!(method, GiMethod::None | GiMethod::Ssgi | GiMethod::Vpl)
        && scene.environment.is_some();
    (emitters || environment).then_some((emitters, environment))
}

pub struct DirectEmittersPass {
    pipeline: ComputePipeline,
    /// The emissive triangles (scenes with them, under `--gi none`).
    emitters: Option<EmitterBuffer>,
    /// The voxel traversal's ray-mask table (binding 4).
    lut: Buffer,
    sampler: vk::Sampler,
    push: GpuGiPush,
}

/// The buffers the pass reads, imported once per frame (both stereo eyes share them).
#[derive(Clone, Copy)]
pub struct DirectEmittersWorld {
    lut: BufferHandle,
    emitters: Option<BufferHandle>,
}

impl DirectEmittersPass {
    /// `light`: [`sampled_light`]'s answer; `target`: the grid the frame voxelizes and the
    /// frame's size; `samples`: K per pixel; `sampler`: the nearest-neighbour sampler.
    pub fn new(
        ctx: &Context,
        (emitters, environment): (bool, bool),
        target: &GiTarget<'_>,
        gi: &crate::gi::GiSettings,
        samples: u32,
        sampler: vk::Sampler,
    ) -> Result<Self, VkError> {
        let scene = target.scene;
        let emitters = match emitters {
            true => EmitterBuffer::new(ctx, scene, target.time_s)?,
            false => None,
        };
        let environment = match environment {
            true => Environment::shader_kind(scene.environment.as_ref()),
            false => 0,
        };
        let pipeline = ctx.compute_pipeline(
            "direct_emitters.comp",
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                HAS_PHONG = target.has_phong || scene.has_ggx(),
                HAS_EMITTERS = emitters.is_some(),
                ENVIRONMENT = environment,
            ],
        )?;
        let lut = ctx.upload_buffer(
            "direct ray mask lut",
            &RayMaskLut::new().to_gpu_bytes(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Self {
            pipeline,
            emitters,
            lut,
            sampler,
            push: GpuGiPush {
                rays: samples.max(1),
                ..GpuGiPush::new(gi, target)
            },
        })
    }

    /// Imports the pass's buffers into this frame's graph (once, before the eyes' passes).
    pub fn import(&self, g: &mut RenderGraph) -> DirectEmittersWorld {
        DirectEmittersWorld {
            lut: g.import_buffer(&self.lut, Access::StorageRead(Shader::Compute)),
            emitters: self.emitters.as_ref().map(|e| e.import(g)),
        }
    }

    /// Declares the pass; returns `direct` with the sampled light added (RGBA32F, alpha kept).
    #[allow(clippy::too_many_arguments)]
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        direct: ImageHandle,
        voxels: ImageHandle,
        world: DirectEmittersWorld,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let radiance = g.create_image(ImageDesc::new_2d("radiance", HDR, w, h));
        let pipe = *self.pipeline;
        let (s, c) = (self.sampler, Shader::Compute);
        // Bindings the shader never reads without Phong/GGX materials, emitters or an
        // environment map get an image or buffer of the right kind.
        let specular = gbuffer.specular.unwrap_or(gbuffer.albedo);
        let environment = scene.environment_map.unwrap_or(gbuffer.albedo);
        let emitters = world.emitters.unwrap_or(world.lut);
        let push = self.push;
        g.add_pass("direct_emitters")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(c))
            .bind_sampled(1, gbuffer.normal, s, c)
            .bind_sampled(2, gbuffer.depth, s, c)
            .bind_sampled(3, voxels, s, c)
            .bind(4, world.lut, Access::StorageRead(c))
            .bind_sampled(5, direct, s, c)
            .bind(8, radiance, Access::StorageWrite(c))
            .bind_sampled(9, specular, s, c)
            .bind_sampled(10, gbuffer.albedo, s, c)
            .bind(14, emitters, Access::StorageRead(c))
            .bind_sampled(15, environment, scene.texture_sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        radiance
    }

    /// Rebuilds the emitter list for `scene` at `t_s` (an emissive object moved).
    pub fn update_scene(&mut self, scene: &Scene, t_s: f32) {
        if let Some(e) = &mut self.emitters {
            e.update(scene, t_s);
        }
    }

    /// Writes the current emitter list into frame slot `slot`'s window.
    pub fn write_slot(&mut self, slot: usize) {
        if let Some(e) = &mut self.emitters {
            e.write_slot(slot);
        }
    }
}

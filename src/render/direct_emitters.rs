//! `direct_emitters`: the direct light of the emissive triangles and of the environment at
//! every G-buffer pixel, with voxel visibility, added to `deferred_direct`'s radiance
//! (`glsl/direct_emitters.comp`; docs/design/emitter-sampling.md, "Direct light").
//!
//! It samples only the light that the frame's GI method does not bring itself, so nothing is
//! counted twice: each method's spec states what its own passes bring
//! ([`crate::gi::MethodSpec::brings_emitters`], [`crate::gi::MethodSpec::brings_environment`];
//! the table method × light is in docs/design/emitter-sampling.md, "Who brings which light").
//!
//! The emitter list is the path tracer's ([`crate::gi::emitters`]); the rays are the GI rays'
//! voxel traversal with the GI settings' offsets and length ([`GpuGiPush`]), their count per
//! pixel `shadow.direct_samples` (in the push constants' `rays`).

use super::gbuffer::Gbuffer;
use super::scene_gpu::SceneInputs;
use super::HDR;
use crate::gi::emitters::EmitterBuffer;
use crate::gi::gi_common::GpuGiPush;
use crate::gi::{EmitterReach, GiMethod, GiTarget};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::{Environment, Scene};
use crate::vk::{vk, Buffer, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use crate::voxel::ray_mask::RayMaskLut;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// What the pass samples (`None` of [`sampled_light`]: nothing, and the pass is not made).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampledLight {
    /// The emissive triangles' light.
    pub emitters: bool,
    /// Of the emitters, only the points the camera does not see: the method gathers the
    /// others' light from the frame ([`EmitterReach::OnScreen`]).
    pub emitters_off_screen_only: bool,
    /// The environment's light.
    pub environment: bool,
}

/// What the pass samples for `method` in `scene`: the light the scene has and the method's
/// own passes do not bring (its spec says which); `None` when nothing (then the pass, and
/// for it the voxel grid, is not made).
pub fn sampled_light(method: GiMethod, scene: &Scene) -> Option<SampledLight> {
    let spec = method.spec();
    let emitters = spec.brings_emitters != EmitterReach::All && scene.has_emission();
    let environment = !spec.brings_environment && scene.environment.is_some();
    (emitters || environment).then_some(SampledLight {
        emitters,
        emitters_off_screen_only: emitters && spec.brings_emitters == EmitterReach::OnScreen,
        environment,
    })
}

pub struct DirectEmittersPass {
    pipeline: ComputePipeline,
    /// The emissive triangles (scenes with them, where the method does not bring them all).
    emitters: Option<EmitterBuffer>,
    /// The voxel traversal's ray-mask table (binding 4).
    lut: Buffer,
    sampler: vk::Sampler,
    push: GpuGiPush,
    /// Frames written so far, by which the samples advance (`ADVANCE`), when the frame
    /// accumulates (TAA); `None`: the samples are the same every frame.
    frames: Option<Arc<AtomicU32>>,
}

/// The buffers the pass reads, imported once per frame (both stereo eyes share them).
#[derive(Clone, Copy)]
pub struct DirectEmittersWorld {
    lut: BufferHandle,
    emitters: Option<BufferHandle>,
}

impl DirectEmittersPass {
    /// `light`: [`sampled_light`]'s answer; `target`: the grid the frame voxelizes and the
    /// frame's size; `samples`: K per pixel; `advance`: the frame accumulates over frames
    /// (TAA), so each frame draws other samples and their average converges (a frame that
    /// does not accumulate keeps its samples, and a still image is the same every frame);
    /// `sampler`: the nearest-neighbour sampler.
    pub fn new(
        ctx: &Context,
        light: SampledLight,
        target: &GiTarget<'_>,
        gi: &crate::gi::GiSettings,
        (samples, advance): (u32, bool),
        sampler: vk::Sampler,
    ) -> Result<Self, VkError> {
        let scene = target.scene;
        let emitters = match light.emitters {
            true => EmitterBuffer::new(ctx, scene, target.time_s)?,
            false => None,
        };
        let environment = match light.environment {
            true => Environment::shader_kind(scene.environment.as_ref()),
            false => 0,
        };
        let pipeline = ctx.compute_pipeline(
            "direct_emitters.comp",
            PushLayout::of::<GpuGiPush>(),
            &crate::spec_constants![
                HAS_PHONG = target.has_phong || scene.has_ggx(),
                HAS_EMITTERS = emitters.is_some(),
                OFF_SCREEN_EMITTERS_ONLY = light.emitters_off_screen_only,
                ADVANCE = advance,
                ENVIRONMENT = environment,
                ENV_SAMPLING = gi.env_sampling && environment == 2,
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
            frames: advance.then(|| Arc::new(AtomicU32::new(0))),
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
        let environment_cdf = scene.environment_cdf.unwrap_or(world.lut);
        let push = self.push;
        let frames = self.frames.clone();
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
            .bind_sampled(15, environment, scene.environment_sampler, c)
            .bind(16, environment_cdf, Access::StorageRead(c))
            .record(move |ctx| {
                // The shader's R2 index: the base seed advanced by the frames written.
                let advanced = frames.as_ref().map_or(0, |f| f.load(Ordering::SeqCst));
                let push = GpuGiPush {
                    seed: push.seed.wrapping_add(advanced),
                    ..push
                };
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

    /// Writes the current emitter list into frame slot `slot`'s window, and counts the frame
    /// (once per frame, before it is recorded).
    pub fn write_slot(&mut self, slot: usize) {
        if let Some(f) = &self.frames {
            f.fetch_add(1, Ordering::SeqCst);
        }
        if let Some(e) = &mut self.emitters {
            e.write_slot(slot);
        }
    }
}

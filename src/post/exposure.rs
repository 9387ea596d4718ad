//! `exposure`: auto exposure from the frame's log-average luminance (`glsl/exposure.comp`;
//! Oetke 2017 §4.4, Reinhard et al. 2002 §3.1). A one-workgroup reduction on the GPU writes
//! the exposure key / L̄ into a persistent buffer, adapted over frames; `tonemap` reads it there
//! (no read-back to the host).

use super::AutoExposure;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Buffer, ComputePipeline, Context, PushLayout, VkError};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// Push constants of `exposure.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuExposurePush {
    pub key: f32,
    pub adaptation: f32,
    /// 1 in the first frame: the exposure jumps to its target.
    pub first_frame: u32,
}

crate::push_constants!(GpuExposurePush {
    key,
    adaptation,
    first_frame
});

/// The state the exposure buffer holds between frames and passes between `exposure` and
/// `tonemap`: the exposure and the log-average luminance it came from.
pub const EXPOSURE_BUFFER_BYTES: u64 = 8;

/// The resting state of an exposure buffer: read by `tonemap`.
pub const EXPOSURE_STATE: Access = Access::StorageRead(Shader::Compute);

/// The reduction pipeline and the persistent exposure buffer.
pub struct ExposurePass {
    pipeline: ComputePipeline,
    buffer: Buffer,
    sampler: vk::Sampler,
    settings: AutoExposure,
    /// Frames recorded, so that the first jumps to its target.
    frames: Arc<AtomicU32>,
}

impl ExposurePass {
    /// `sampler`: nearest (one texel per pixel).
    pub fn new(
        ctx: &Context,
        settings: AutoExposure,
        sampler: vk::Sampler,
    ) -> Result<Self, VkError> {
        let pipeline =
            ctx.compute_pipeline("exposure.comp", PushLayout::of::<GpuExposurePush>(), &[])?;
        let buffer = ctx.upload_buffer(
            "exposure",
            bytemuck::bytes_of(&[1.0f32, 0.0]),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        Ok(Self {
            pipeline,
            buffer,
            sampler,
            settings,
            frames: Arc::new(AtomicU32::new(0)),
        })
    }

    /// Declares the reduction of `radiance`; returns the exposure buffer for `tonemap`.
    pub fn declare(&self, g: &mut RenderGraph, radiance: ImageHandle) -> BufferHandle {
        let buffer = g.import_buffer(&self.buffer, EXPOSURE_STATE);
        let pipe = *self.pipeline;
        let settings = self.settings;
        let frames = self.frames.clone();
        g.add_pass("exposure")
            .pipeline(&pipe)
            .bind_sampled(0, radiance, self.sampler, Shader::Compute)
            .bind(1, buffer, Access::StorageReadWrite(Shader::Compute))
            .record(move |ctx| {
                let push = GpuExposurePush {
                    key: settings.key,
                    adaptation: settings.adaptation,
                    first_frame: u32::from(frames.fetch_add(1, Ordering::SeqCst) == 0),
                };
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(1, 1, 1);
            });
        buffer
    }
}

//! `gbuffer_view`: a G-buffer channel — albedo, world-space normal or camera distance — shown
//! instead of the lit image (`--debug gbuffer-albedo|gbuffer-normal|gbuffer-distance`), the
//! values the lighting is computed from (`glsl/gbuffer_view.comp`).

use super::gbuffer::Gbuffer;
use super::scene_gpu::SceneInputs;
use super::HDR;
use crate::eval::HdrImage;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// Which channel the view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GbufferChannel {
    Albedo,
    Normal,
    /// Distance from the camera, meters.
    Distance,
}

impl GbufferChannel {
    fn shader_id(self) -> u32 {
        match self {
            GbufferChannel::Albedo => 0,
            GbufferChannel::Normal => 1,
            GbufferChannel::Distance => 2,
        }
    }
}

/// The channel a debug view shows (`None`: not a G-buffer view).
pub fn channel(view: crate::voxel::debug_view::DebugView) -> Option<GbufferChannel> {
    use crate::voxel::debug_view::DebugView;
    match view {
        DebugView::GbufferAlbedo => Some(GbufferChannel::Albedo),
        DebugView::GbufferNormal => Some(GbufferChannel::Normal),
        DebugView::GbufferDistance => Some(GbufferChannel::Distance),
        _ => None,
    }
}

/// Push constants of `gbuffer_view.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuGbufferViewPush {
    channel: u32,
    inv_distance_m: f32,
}

crate::push_constants!(GpuGbufferViewPush {
    channel,
    inv_distance_m
});

pub struct GbufferViewPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
    channel: GbufferChannel,
    /// Distance drawn black (the scene's bounding-box diagonal), meters.
    far_m: f32,
}

impl GbufferViewPass {
    pub fn new(
        ctx: &Context,
        sampler: vk::Sampler,
        channel: GbufferChannel,
        far_m: f32,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "gbuffer_view.comp",
            crate::vk::PushLayout::of::<GpuGbufferViewPush>(),
            &[],
        )?;
        Ok(Self {
            pipeline,
            sampler,
            channel,
            far_m,
        })
    }

    /// Declares the view; returns its value image (RGBA32F) and color image (RGBA8 sRGB).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        (w, h): (u32, u32),
    ) -> (ImageHandle, ImageHandle) {
        let value = g.create_image(ImageDesc::new_2d("gbuffer view value", HDR, w, h));
        let color = g.create_image(ImageDesc::new_2d(
            "gbuffer view color",
            vk::Format::R8G8B8A8_UNORM,
            w,
            h,
        ));
        let pipe = *self.pipeline;
        let push = GpuGbufferViewPush {
            channel: self.channel.shader_id(),
            inv_distance_m: 1.0 / self.far_m.max(1e-6),
        };
        let (s, c) = (self.sampler, Shader::Compute);
        g.add_pass("gbuffer_view")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(c))
            .bind_sampled(1, gbuffer.albedo, s, c)
            .bind_sampled(2, gbuffer.normal, s, c)
            .bind_sampled(3, gbuffer.depth, s, c)
            .bind(4, value, Access::StorageWrite(c))
            .bind(5, color, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        (value, color)
    }

    /// What the view shows, with the share of pixels on geometry and the channel's range.
    pub fn describe(&self, value: &HdrImage) -> String {
        let on: Vec<&[f32; 3]> = value
            .data
            .iter()
            .filter(|p| p.iter().any(|c| *c != 0.0))
            .collect();
        let share = 100.0 * on.len() as f64 / value.data.len().max(1) as f64;
        let (lo, hi) = on
            .iter()
            .flat_map(|p| p.iter())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &c| {
                (lo.min(c), hi.max(c))
            });
        match self.channel {
            GbufferChannel::Albedo => format!(
                "G-buffer albedo: {share:.1}% of pixels on geometry, albedo {lo:.3}..{hi:.3} \
                 (the value image holds linear albedo)"
            ),
            GbufferChannel::Normal => format!(
                "G-buffer normal: {share:.1}% of pixels on geometry (color = (n + 1) / 2; the \
                 value image holds the world-space unit normal)"
            ),
            GbufferChannel::Distance => format!(
                "G-buffer distance: {share:.1}% of pixels on geometry, {lo:.3}..{hi:.3} m from \
                 the camera (white = 0, black = {:.3} m)",
                self.far_m
            ),
        }
    }
}

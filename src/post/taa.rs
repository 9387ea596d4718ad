//! `taa`: temporal anti-aliasing of the linear HDR radiance (`glsl/taa.comp`; Oetke 2017 §4.5,
//! after Karis 2014). The renderer jitters the projection of every frame by a Halton(2,3)
//! sub-pixel offset ([`TaaPass::begin_frame`] returns it; [`jitter_matrix`] applied to the
//! view-projection and its camera-relative inverse, used by every pass of the frame, so
//! G-buffer, depth and every position reconstructed from them agree);
//! this pass reprojects the history with the depth and the previous frame's un-jittered camera,
//! clips it in YCoCg to the current 3×3 neighbourhood and blends it with the current frame.
//! A copy (`taa_history`) keeps the result for the next frame. In scenes with moving objects
//! the G-buffer's motion vectors replace the camera-only reprojection at surface pixels.
//!
//! **Upsampling** (the viewer's dynamic resolution, `post.upscale = "taa"`): the history and
//! the resolved image have a larger size than the frame (`PostSettings::upsample_to`). Each
//! output pixel reprojects the history at its own (un-jittered) centre and gathers the 3×3
//! frame pixels around it, each weighted by the distance of its jittered sample position to
//! the output pixel's centre (Karis 2014's Blackman-Harris fit exp(−2.29 d²), as in Unreal's
//! TAAU and the FSR 2 reconstruction, which weighs samples by that distance). The history
//! keeps the weighted mean of its samples and their total weight (in alpha, capped at
//! 1 / the current frame's TAA weight, so a full history is TAA's exponential mean): a pixel
//! that no sample of this frame lies near keeps its history, and a still camera fills every
//! output pixel over the jitter cycle.

use super::TaaSettings;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, Image, ImageDesc, PushLayout, VkError};
use glam::{Mat4, Vec2, Vec3};
use std::sync::{Arc, Mutex};

/// Push constants of `taa.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTaaPush {
    /// Previous un-jittered view-projection × inverse of this frame's un-jittered one.
    pub reproject: [f32; 16],
    pub jitter_ndc: [f32; 2],
    pub current_weight: f32,
    pub has_history: u32,
}

crate::push_constants!(GpuTaaPush {
    reproject,
    jitter_ndc,
    current_weight,
    has_history
});

/// The radical inverse of `i` in `base` (the Halton sequence's element i), in [0, 1).
pub fn halton(mut i: u32, base: u32) -> f32 {
    let (mut f, mut r) = (1.0f32, 0.0f32);
    while i > 0 {
        f /= base as f32;
        r += f * (i % base) as f32;
        i /= base;
    }
    r
}

/// Halton(2,3) points cycled by the jitter: 16 cover the pixel evenly (Karis 2014 uses 8–16).
pub const JITTER_CYCLE: u32 = 16;

/// The sub-pixel offset of frame `frame`, in pixels, in [−0.5, 0.5)²: Halton(2,3) element
/// (frame mod 16) + 1 (element 0 is the corner (0, 0)).
pub fn jitter_px(frame: u32) -> Vec2 {
    let i = frame % JITTER_CYCLE + 1;
    Vec2::new(halton(i, 2), halton(i, 3)) - 0.5
}

/// `view_proj` moved by `jitter_ndc` in NDC: clip x, y gain jitter · w, so every point moves
/// by exactly `jitter_ndc` on the screen and depth is unchanged.
pub fn jittered(view_proj: Mat4, jitter_ndc: Vec2) -> Mat4 {
    jitter_matrix(jitter_ndc) * view_proj
}

/// The clip-space shift by `jitter_ndc`: x += j.x·w, y += j.y·w. Applied on the left of a
/// view-projection (and its inverse on the right of an inverse), so that the renderer can
/// jitter the camera-relative inverse exactly, without inverting a world-space matrix.
pub fn jitter_matrix(jitter_ndc: Vec2) -> Mat4 {
    Mat4::from_translation(Vec3::new(jitter_ndc.x, jitter_ndc.y, 0.0))
}

/// What the host knows between frames: frames blended so far and the last camera.
#[derive(Debug)]
struct TaaState {
    frames: u32,
    prev_view_proj: Mat4,
    push: GpuTaaPush,
}

/// The TAA pipeline, its history (the output's size, RGBA32F) and the per-frame state.
pub struct TaaPass {
    pipeline: ComputePipeline,
    history: Image,
    sampler: vk::Sampler,
    settings: TaaSettings,
    /// The frame's size: the jitter is a fraction of its pixels.
    size: (u32, u32),
    /// The history's and the resolved image's size: `size`, or larger when upsampling.
    out: (u32, u32),
    state: Arc<Mutex<TaaState>>,
}

impl TaaPass {
    /// The history image of a `w`×`h` frame (also counted by the renderer's memory check).
    pub fn history_desc((w, h): (u32, u32)) -> ImageDesc {
        ImageDesc::new_2d("taa history", vk::Format::R32G32B32A32_SFLOAT, w, h)
            .with_usage(vk::ImageUsageFlags::SAMPLED)
    }

    /// `sampler`: nearest (the shader filters the history by hand). `motion`: the G-buffer
    /// has motion vectors, [`TaaPass::declare`] gets them. `out`: the resolved size, `size`
    /// or larger (upsampling).
    pub fn new(
        ctx: &Context,
        settings: TaaSettings,
        (w, h): (u32, u32),
        out: (u32, u32),
        sampler: vk::Sampler,
        motion: bool,
    ) -> Result<Self, VkError> {
        let upsample = out != (w, h);
        let pipeline = ctx.compute_pipeline(
            "taa.comp",
            PushLayout::of::<GpuTaaPush>(),
            &crate::spec_constants![MOTION = motion, UPSAMPLE = upsample],
        )?;
        let history = ctx.create_zeroed_image(
            &Self::history_desc(out),
            Access::Sampled(Shader::Compute).info().layout,
        )?;
        Ok(Self {
            pipeline,
            history,
            sampler,
            settings,
            size: (w, h),
            out,
            state: Arc::new(Mutex::new(TaaState {
                frames: 0,
                prev_view_proj: Mat4::IDENTITY,
                push: bytemuck::Zeroable::zeroed(),
            })),
        })
    }

    /// Starts a frame whose un-jittered view-projection is `view_proj` (call before recording
    /// it): sets the pass's push constants and returns the frame's jitter in NDC units
    /// (the frame renders with [`jittered`]`(view_proj, jitter)`).
    pub fn begin_frame(&self, view_proj: Mat4) -> Vec2 {
        let (w, h) = self.size;
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let jitter_ndc = jitter_px(s.frames) * Vec2::new(2.0 / w as f32, 2.0 / h as f32);
        let reproject = s.prev_view_proj * view_proj.inverse();
        // A plain mean while fewer frames than 1/(1 − α) are blended, then the exponential
        // weight 1 − α: a static view converges as fast as the history weight allows.
        let current_weight = (1.0 - self.settings.history_weight).max(1.0 / (s.frames + 1) as f32);
        s.push = GpuTaaPush {
            reproject: reproject.to_cols_array(),
            jitter_ndc: jitter_ndc.to_array(),
            current_weight,
            has_history: u32::from(s.frames > 0),
        };
        s.frames = s.frames.saturating_add(1);
        s.prev_view_proj = view_proj;
        jitter_ndc
    }

    /// Declares `taa` (current + depth [+ motion vectors] + history → resolved) and
    /// `taa_history` (resolved → history); returns the resolved radiance. `motion` must be
    /// given exactly when the pass was made with motion vectors.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        radiance: ImageHandle,
        depth: ImageHandle,
        motion: Option<ImageHandle>,
    ) -> ImageHandle {
        let (w, h) = self.out;
        let c = Shader::Compute;
        let history = g.import_image(&self.history, Access::Sampled(c));
        let resolved = g.create_image(ImageDesc::new_2d(
            "taa resolved",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let pipe = *self.pipeline;
        let state = self.state.clone();
        g.add_pass("taa")
            .pipeline(&pipe)
            .bind_sampled(0, radiance, self.sampler, c)
            .bind_sampled(1, depth, self.sampler, c)
            .bind_sampled(2, history, self.sampler, c)
            .bind(3, resolved, Access::StorageWrite(c))
            // Without motion vectors the shader never reads binding 4; the depth fills it.
            .bind_sampled(4, motion.unwrap_or(depth), self.sampler, c)
            .record(move |ctx| {
                let push = state.lock().unwrap_or_else(|e| e.into_inner()).push;
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        let extent = vk::Extent3D {
            width: w,
            height: h,
            depth: 1,
        };
        g.add_pass("taa_history")
            .read(resolved, Access::TransferRead)
            .write(history, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd
                    .copy_image(ctx.image(resolved).raw, ctx.image(history).raw, extent)
            });
        resolved
    }

    /// Frames rendered since the pass was made.
    pub fn frames(&self) -> u32 {
        self.state.lock().unwrap_or_else(|e| e.into_inner()).frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halton(2): 1/2, 1/4, 3/4, 1/8; Halton(3): 1/3, 2/3, 1/9 — the radical inverses.
    #[test]
    fn halton_is_the_radical_inverse() {
        let h2: Vec<f32> = (1..5).map(|i| halton(i, 2)).collect();
        assert_eq!(h2, [0.5, 0.25, 0.75, 0.125]);
        for (i, want) in [(1, 1.0 / 3.0), (2, 2.0 / 3.0), (3, 1.0 / 9.0)] {
            assert!((halton(i, 3) - want).abs() < 1e-7);
        }
    }

    /// One cycle of jitters averages to the pixel centre within 1/16 pixel (a stratified
    /// cover of [−0.5, 0.5)²), and every offset stays inside the pixel.
    #[test]
    fn jitter_cycle_covers_the_pixel_evenly() {
        let pts: Vec<Vec2> = (0..JITTER_CYCLE).map(jitter_px).collect();
        let mean = pts.iter().copied().sum::<Vec2>() / JITTER_CYCLE as f32;
        assert!(mean.abs().max_element() < 1.0 / 16.0, "{mean}");
        assert!(pts.iter().all(|p| p.abs().max_element() < 0.5));
    }

    /// The jittered matrix moves every projected point by exactly the jitter and keeps depth.
    #[test]
    fn jitter_moves_projected_points_by_the_offset() {
        let vp = glam::camera::rh::proj::directx::perspective(1.0, 1.5, 0.1, 50.0)
            * glam::camera::rh::view::look_at_mat4(Vec3::new(1.0, 2.0, 5.0), Vec3::ZERO, Vec3::Y);
        let j = Vec2::new(0.01, -0.02);
        for p in [Vec3::new(0.3, -0.2, 0.1), Vec3::new(-2.0, 1.0, -4.0)] {
            let a = vp.project_point3(p);
            let b = jittered(vp, j).project_point3(p);
            assert!((b.truncate() - a.truncate() - j).abs().max_element() < 1e-6);
            assert!((b.z - a.z).abs() < 1e-6);
        }
    }
}

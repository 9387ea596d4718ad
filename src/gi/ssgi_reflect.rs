//! Screen-space reflections of `--gi ssgi` (Oetke 2017 §5.4), in scenes with Phong or GGX
//! materials unless `--ssr off`; other scenes have none of these passes or images.
//!
//! Passes (`glsl/ssgi_reflect*.comp`):
//! - `ssgi_reflect_hiz[k]`: a full mip chain of two pyramids from the GI pyramid's level 0:
//!   the nearest inverse view depth 1/z (the conservative Hi-Z the march needs; the GI
//!   pyramid's voting or fast depth keeps one child, so a thin near surface could vanish from
//!   a coarse level) and the lit colour by 2×2 box average;
//! - `ssgi_reflect`: one ray per Phong or GGX pixel, marched on the Hi-Z pyramid: along the
//!   mirror direction, read at the colour pyramid's level matching the lobe's cone footprint
//!   (`--ssr-rays mirror`), or sampled from the lobe anew every frame and read at the finest
//!   level, weighted for the split sum (`--ssr-rays lobe`); fades at the screen's edge, near
//!   the maximum distance, toward the camera, at back faces and for misses; blended with the
//!   reprojected history. Output (a·L, a);
//! - `ssgi_reflect_blur`: a 3×3 geometry-aware blur, and the unblurred value into the history.
//!
//! `ssgi_upsample` completes L_spec = a·L + (1 − a)·E/π (the diffuse fallback) and combines
//! it by Eq. 2.19 (GGX) or with the normalized Phong lobe's directional albedo ρs (n·v).
//!
//! The reflected colour is the GI pyramid's lit colour: this frame's direct light (diffuse
//! and specular) with emission, plus last frame's diffuse indirect light (the feedback);
//! last frame's specular indirect light (reflections seen in reflections) is not in it.

use super::{GiInputs, GiTarget, SsrRays};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, Image, ImageDesc, PushLayout, Sampler, VkError};
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// The hit shell behind a surface, relative to its view depth.
pub const THICKNESS: f32 = 0.05;
/// March steps per ray (each one cell of some Hi-Z level).
pub const MAX_STEPS: i32 = 96;

/// Push constants of `glsl/ssgi_reflect.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSsrPush {
    max_distance_m: f32,
    thickness: f32,
    pixel_angle: f32,
    history_weight: f32,
    levels: i32,
    max_steps: i32,
    frame: u32,
}
crate::push_constants!(GpuSsrPush {
    max_distance_m,
    thickness,
    pixel_angle,
    history_weight,
    levels,
    max_steps,
    frame
});

/// Mip levels of a full chain over a `width`×`height` frame (down to 1×1).
pub fn pyramid_levels(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// The size of mip `k` of a `width`×`height` image: halved, rounded down (Vulkan's rule).
pub fn mip_size(width: u32, height: u32, k: u32) -> (u32, u32) {
    ((width >> k).max(1), (height >> k).max(1))
}

/// The GI pyramid's level 0 and the G-buffer images the reflections read, the GI history
/// (whose w holds last frame's clip w per pixel) with the previous camera, and the split-sum
/// table (GGX scenes; lobe samples divide by its A + B).
pub struct SsrInputs {
    pub fine_pos: ImageHandle,
    pub fine_nrm: ImageHandle,
    pub lit_color: ImageHandle,
    pub specular: ImageHandle,
    pub gi_history: ImageHandle,
    pub prev_camera: BufferHandle,
    pub brdf_lut: Option<ImageHandle>,
}

/// The reflections' pipelines, sampler and persistent history.
pub struct Ssr {
    hiz_first: ComputePipeline,
    hiz: ComputePipeline,
    reflect: ComputePipeline,
    blur: ComputePipeline,
    /// Linear, with linear mip filtering: the cone lookup blends between colour levels.
    linear: Sampler,
    /// Last frame's traced (a·L, a) per pixel, before the blur.
    history: Image,
    push: GpuSsrPush,
    /// Frames traced so far: the lobe samples' index (not reset with the GI accumulation, so
    /// a moving camera keeps blending the reprojected history with τ).
    frames: Arc<AtomicU32>,
}

impl Ssr {
    /// The persistent reflection history at the frame's `size` (also counted by the frame's
    /// memory check before anything is allocated).
    pub fn history_desc((w, h): (u32, u32)) -> ImageDesc {
        ImageDesc::new_2d("ssr history", vk::Format::R32G32B32A32_SFLOAT, w, h)
            .with_usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED)
    }

    pub fn new(
        ctx: &Context,
        target: &GiTarget<'_>,
        history_weight: f32,
        rays: SsrRays,
    ) -> Result<Self, VkError> {
        let hiz_first = ctx.compute_pipeline(
            "ssgi_reflect_hiz.comp",
            None,
            &crate::spec_constants![FIRST = true],
        )?;
        let hiz = ctx.compute_pipeline(
            "ssgi_reflect_hiz.comp",
            None,
            &crate::spec_constants![FIRST = false],
        )?;
        let reflect = ctx.compute_pipeline(
            "ssgi_reflect.comp",
            PushLayout::of::<GpuSsrPush>(),
            &crate::spec_constants![LOBE = rays == SsrRays::Lobe],
        )?;
        let blur = ctx.compute_pipeline("ssgi_reflect_blur.comp", None, &[])?;
        let (w, h) = target.size;
        let history = ctx.create_zeroed_image(
            &Self::history_desc(target.size),
            Access::Sampled(Shader::Compute).info().layout,
        )?;
        let camera = &target.scene.camera;
        let push = GpuSsrPush {
            max_distance_m: max_distance_m(target),
            thickness: THICKNESS,
            pixel_angle: 2.0 * (camera.fov_y_deg.to_radians() * 0.5).tan() / h as f32,
            history_weight,
            levels: pyramid_levels(w, h) as i32,
            max_steps: MAX_STEPS,
            frame: 0,
        };
        Ok(Self {
            hiz_first,
            hiz,
            reflect,
            blur,
            linear: ctx.create_sampler(vk::Filter::LINEAR, false)?,
            history,
            push,
            frames: Arc::new(AtomicU32::new(0)),
        })
    }

    /// Declares the reflection passes; returns the blurred (a·L, a) at the frame's size.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        r: &SsrInputs,
    ) -> ImageHandle {
        let c = Shader::Compute;
        let (hiz, color) = self.add_pyramids(g, i, sampler, r);
        let history = g.import_image(&self.history, Access::Sampled(c));
        let desc = |name: &str| {
            ImageDesc::new_2d(name, vk::Format::R32G32B32A32_SFLOAT, i.width, i.height)
        };
        let traced = g.create_image(desc("ssr traced"));
        let blurred = g.create_image(desc("ssr blurred"));
        let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
        let (pipe, push) = (*self.reflect, self.push);
        let frames = self.frames.clone();
        // Without the table (no GGX materials) the shader never reads it; positions fill it.
        let lut = r.brdf_lut.unwrap_or(r.fine_pos);
        g.add_pass("ssgi_reflect")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, r.fine_pos, sampler, c)
            .bind_sampled(2, i.normal, sampler, c)
            .bind_sampled(3, r.specular, sampler, c)
            .bind_sampled(4, hiz, sampler, c)
            .bind_sampled(5, color, self.linear.raw, c)
            .bind_sampled(6, history, sampler, c)
            .bind_sampled(7, r.gi_history, sampler, c)
            .bind(8, r.prev_camera, Access::StorageRead(c))
            .bind(9, traced, Access::StorageWrite(c))
            .bind_sampled(10, lut, sampler, c)
            .record(move |ctx| {
                let push = GpuSsrPush {
                    frame: frames.fetch_add(1, Ordering::SeqCst),
                    ..push
                };
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        let pipe = *self.blur;
        g.add_pass("ssgi_reflect_blur")
            .pipeline(&pipe)
            .bind_sampled(0, traced, sampler, c)
            .bind_sampled(1, r.fine_pos, sampler, c)
            .bind_sampled(2, r.fine_nrm, sampler, c)
            .bind_sampled(3, r.specular, sampler, c)
            .bind(4, blurred, Access::StorageWrite(c))
            .bind(5, history, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        blurred
    }

    /// Declares `ssgi_reflect_hiz[k]` for every level; returns the Hi-Z and colour pyramids.
    fn add_pyramids(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        r: &SsrInputs,
    ) -> (ImageHandle, ImageHandle) {
        let c = Shader::Compute;
        let levels = self.push.levels as u32;
        let pyramid = |g: &mut RenderGraph, name: &str, format| {
            g.create_image(ImageDesc::new_2d(name, format, i.width, i.height).with_mips(levels))
        };
        let hiz = pyramid(g, "ssr hi-z", vk::Format::R32_SFLOAT);
        let color = pyramid(g, "ssr lit colour", vk::Format::R16G16B16A16_SFLOAT);
        for k in 0..levels {
            let (w, h) = mip_size(i.width, i.height, k);
            let groups = (w.div_ceil(8), h.div_ceil(8));
            let sampled = Access::Sampled(c);
            let write = Access::StorageWrite(c);
            let pass = g.add_pass(&format!("ssgi_reflect_hiz[{k}]"));
            let (pass, pipe) = if k == 0 {
                let pipe = *self.hiz_first;
                let pass = pass
                    .pipeline(&pipe)
                    .bind_sampled(0, r.fine_pos, sampler, c)
                    .bind_sampled(1, r.lit_color, sampler, c);
                (pass, pipe)
            } else {
                let pipe = *self.hiz;
                let pass = pass
                    .pipeline(&pipe)
                    .bind_mip(0, hiz, k - 1, sampled, Some(sampler))
                    .bind_mip(1, color, k - 1, sampled, Some(sampler));
                (pass, pipe)
            };
            pass.bind_mip(2, hiz, k, write, None)
                .bind_mip(3, color, k, write, None)
                .bind(4, i.frame, Access::StorageRead(c))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
        }
        (hiz, color)
    }
}

/// The rays' length: the scene's bounding-box diagonal (the camera's far distance for an
/// empty or unbounded scene).
fn max_distance_m(target: &GiTarget<'_>) -> f32 {
    let b = target.scene.aabb_at(target.time_s);
    let diagonal = (b.max - b.min).length();
    if diagonal.is_finite() && diagonal > 0.0 {
        diagonal
    } else {
        target.scene.camera.far
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_match_glsl() {
        crate::vk::check_push_against(&["ssgi_reflect.comp"], PushLayout::of::<GpuSsrPush>())
            .unwrap_or_else(|e| panic!("{e}"));
    }

    /// A full chain ends at 1×1, halving rounded down: 128 → 8 levels (128, 64, …, 1);
    /// 129×64 → 8 (129, 64, 32, 16, 8, 4, 2, 1 wide; 64, …, 1, 1 high); 1 → 1.
    #[test]
    fn the_pyramid_reaches_one_texel() {
        assert_eq!(pyramid_levels(128, 128), 8);
        assert_eq!(pyramid_levels(129, 64), 8);
        assert_eq!(pyramid_levels(1, 1), 1);
        assert_eq!(mip_size(129, 64, 7), (1, 1));
        assert_eq!(mip_size(129, 64, 1), (64, 32));
    }
}

//! `shadow_texels`: shadow aliasing as a debug view (`--debug shadow-texels`; Dachsbacher
//! 2014, part 3, A.3): per pixel the predicted on-screen size d_i ≈ d_s·(r_s/r_i)·
//! (cos α_i / cos α_s) of the shadow-map texel that shades it, in pixels
//! (`glsl/shadow_texels.comp` has the terms). Above one pixel the map is too coarse there.

use super::gbuffer::Gbuffer;
use super::scene_gpu::SceneInputs;
use super::HDR;
use crate::eval::HdrImage;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// Push constants of `shadow_texels.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuShadowTexelsPush {
    pixel_scale: f32,
}

crate::push_constants!(GpuShadowTexelsPush { pixel_scale });

pub struct ShadowTexelsPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
    /// Pixels per meter at one meter of view depth: height / (2 tan(fov_y / 2)).
    pixel_scale: f32,
}

impl ShadowTexelsPass {
    pub fn new(
        ctx: &Context,
        sampler: vk::Sampler,
        camera: &crate::scene::Camera,
        height: u32,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "shadow_texels.comp",
            crate::vk::PushLayout::of::<GpuShadowTexelsPush>(),
            &[],
        )?;
        Ok(Self {
            pipeline,
            sampler,
            pixel_scale: pixel_scale(camera, height),
        })
    }

    /// Declares the view; returns its value image (RGBA32F: d_i in pixels, the texel in
    /// meters, the shadow view's index) and color image (RGBA8).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        (w, h): (u32, u32),
    ) -> (ImageHandle, ImageHandle) {
        let value = g.create_image(ImageDesc::new_2d("shadow texels value", HDR, w, h));
        let color = g.create_image(ImageDesc::new_2d(
            "shadow texels color",
            vk::Format::R8G8B8A8_UNORM,
            w,
            h,
        ));
        let pipe = *self.pipeline;
        let push = GpuShadowTexelsPush {
            pixel_scale: self.pixel_scale,
        };
        let (s, c) = (self.sampler, Shader::Compute);
        g.add_pass("shadow_texels")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(c))
            .bind_sampled(1, gbuffer.normal, s, c)
            .bind_sampled(2, gbuffer.depth, s, c)
            .bind(3, value, Access::StorageWrite(c))
            .bind(4, color, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        (value, color)
    }
}

/// Pixels per meter at one meter of view depth for `camera` in an image `height` pixels high.
pub fn pixel_scale(camera: &crate::scene::Camera, height: u32) -> f32 {
    height as f32 / (2.0 * (0.5 * camera.fov_y_deg.to_radians()).tan())
}

/// Shares of the lit pixels whose shadow texel is above one and above two pixels, and the
/// median d_i, from the view's value image.
pub fn texel_stats(value: &HdrImage) -> (f64, f64, f32) {
    let mut d: Vec<f32> = value
        .data
        .iter()
        .filter(|p| p[0] > 0.0)
        .map(|p| p[0])
        .collect();
    let n = d.len().max(1) as f64;
    let above = |t: f32| 100.0 * d.iter().filter(|&&x| x > t).count() as f64 / n;
    let (a1, a2) = (above(1.0), above(2.0));
    d.sort_by(f32::total_cmp);
    let median = d.get(d.len() / 2).copied().unwrap_or(0.0);
    (a1, a2, median)
}

/// What the view shows, with its statistics.
pub fn describe(value: &HdrImage) -> String {
    let (a1, a2, median) = texel_stats(value);
    format!(
        "shadow texels: predicted on-screen size of the shadow texel shading each pixel \
         (blue <= 1/4 px, green 1 px, red >= 4 px, grey unlit; the value image holds d_i in \
         pixels, the texel in meters and the shadow view); lit pixels: median {median:.2} px, \
         {a1:.1}% above 1 px, {a2:.1}% above 2 px"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_layout_matches_the_shader() {
        crate::vk::check_push_against(
            &["shadow_texels.comp"],
            crate::vk::PushLayout::of::<GpuShadowTexelsPush>(),
        )
        .unwrap();
    }
}

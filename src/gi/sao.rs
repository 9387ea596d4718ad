//! `sao` and `sao_blur`: Scalable Ambient Obscurance as modified by Oetke 2017 §2.5 (after
//! McGuire, Mara and Luebke 2012) at half resolution, then a depth-aware separable blur; the
//! composite multiplies the indirect light by it (`glsl/gi_composite.comp`). The AO term only
//! darkens indirect light: the voxel methods' indirect light has visibility, but the filter and
//! the coarse grid blur away small-scale occlusion, which SAO puts back.

use super::{GiInputs, SaoSettings};
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};

/// Push constants of `glsl/sao.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSaoPush {
    pub radius_m: f32,
    pub bias: f32,
    pub contrast: f32,
    pub epsilon_m2: f32,
    /// S': the height in pixels of a 1 m object at 1 m view depth, H / (2 tan(fov_y / 2)).
    pub px_per_m_at_1m: f32,
    pub taps: u32,
    pub spiral_turns: f32,
    pub seed: u32,
}

crate::push_constants!(GpuSaoPush {
    radius_m,
    bias,
    contrast,
    epsilon_m2,
    px_per_m_at_1m,
    taps,
    spiral_turns,
    seed
});

impl GpuSaoPush {
    /// The push of `s` for a camera of vertical field of view `fov_y_deg` and a frame
    /// `height_px` pixels high.
    pub fn new(s: &SaoSettings, fov_y_deg: f32, height_px: u32, seed: u32) -> Self {
        Self {
            radius_m: s.radius_m,
            bias: s.bias,
            contrast: s.contrast,
            epsilon_m2: s.epsilon_m2,
            px_per_m_at_1m: height_px as f32 / (2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            taps: SaoSettings::TAPS,
            spiral_turns: SaoSettings::SPIRAL_TURNS,
            seed,
        }
    }
}

/// Push constants of `glsl/sao_blur.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSaoBlurPush {
    direction: [i32; 2],
    depth_sigma_rel: f32,
}

crate::push_constants!(GpuSaoBlurPush {
    direction,
    depth_sigma_rel
});

/// The blur's depth tolerance σ_z relative to the view distance: 2% keeps a floor's taps
/// (depth changing by about a texel's footprint) and drops an object a few cm in front of a
/// wall at a few meters (Oetke 2017 §2.5 uses σ = mix(0.01, 0.25, d)/far in normalized depth).
const BLUR_DEPTH_SIGMA_REL: f32 = 0.02;

/// The SAO and blur pipelines.
pub struct Sao {
    sao: ComputePipeline,
    blur: ComputePipeline,
    push: GpuSaoPush,
}

impl Sao {
    pub fn new(ctx: &Context, push: GpuSaoPush) -> Result<Self, VkError> {
        let sao = ctx.compute_pipeline("sao.comp", PushLayout::of::<GpuSaoPush>(), &[])?;
        let blur =
            ctx.compute_pipeline("sao_blur.comp", PushLayout::of::<GpuSaoBlurPush>(), &[])?;
        Ok(Self { sao, blur, push })
    }

    /// Declares `sao` and the horizontal and vertical `sao_blur`; returns the blurred AO term
    /// (R32F, half the frame's size rounded up; texel (x, y) is pixel (2x, 2y)'s).
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
    ) -> ImageHandle {
        let (w, h) = (i.width.div_ceil(2), i.height.div_ceil(2));
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let c = Shader::Compute;
        let ao_image = |g: &mut RenderGraph, name: &str| {
            g.create_image(ImageDesc::new_2d(name, vk::Format::R32_SFLOAT, w, h))
        };
        let raw = ao_image(g, "sao");
        let (pipe, push) = (*self.sao, self.push);
        g.add_pass("sao")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.normal, sampler, c)
            .bind_sampled(2, i.depth, sampler, c)
            .bind(3, raw, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        let mut current = raw;
        for (axis, direction) in [("h", [1, 0]), ("v", [0, 1])] {
            let out = ao_image(g, &format!("sao blurred {axis}"));
            let bp = GpuSaoBlurPush {
                direction,
                depth_sigma_rel: BLUR_DEPTH_SIGMA_REL,
            };
            let pipe = *self.blur;
            g.add_pass(&format!("sao_blur[{axis}]"))
                .pipeline(&pipe)
                .bind(0, i.frame, Access::StorageRead(c))
                .bind_sampled(1, i.depth, sampler, c)
                .bind_sampled(2, current, sampler, c)
                .bind(3, out, Access::StorageWrite(c))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&bp));
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
            current = out;
        }
        current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_match_glsl() {
        crate::vk::check_push_against(&["sao.comp"], PushLayout::of::<GpuSaoPush>()).unwrap();
        crate::vk::check_push_against(&["sao_blur.comp"], PushLayout::of::<GpuSaoBlurPush>())
            .unwrap();
    }
}

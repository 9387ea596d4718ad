//! `sao_depth`, `sao`, `sao_blur` and `sao_upsample`: Scalable Ambient Obscurance as modified
//! by Oetke 2017 §2.5 (after McGuire, Mara and Luebke 2012). `sao_depth[k]` builds a pyramid
//! of view depth and normal (level 0 the frame's, each coarser level a rotated-grid subsample
//! of the finer), `sao` evaluates the estimator at half resolution with far taps reading
//! coarser levels, `sao_blur[h|v]` is a depth-aware separable blur, and `sao_upsample` brings
//! the term to the frame by joint bilateral upsampling against the full-resolution depth; the
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
    /// Levels of the depth pyramid ([`depth_levels`]).
    pub depth_levels: u32,
}

crate::push_constants!(GpuSaoPush {
    radius_m,
    bias,
    contrast,
    epsilon_m2,
    px_per_m_at_1m,
    taps,
    spiral_turns,
    seed,
    depth_levels
});

impl GpuSaoPush {
    /// The push of `s` for a camera of vertical field of view `fov_y_deg` and a frame of
    /// `(width, height)` pixels.
    pub fn new(
        s: &SaoSettings,
        fov_y_deg: f32,
        (width_px, height_px): (u32, u32),
        seed: u32,
    ) -> Self {
        Self {
            radius_m: s.radius_m,
            bias: s.bias,
            contrast: s.contrast,
            epsilon_m2: s.epsilon_m2,
            px_per_m_at_1m: height_px as f32 / (2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            taps: s.taps,
            spiral_turns: SaoSettings::SPIRAL_TURNS,
            seed,
            depth_levels: depth_levels(width_px, height_px),
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

/// Push constants of `glsl/sao_upsample.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSaoUpsamplePush {
    depth_sigma_rel: f32,
}

crate::push_constants!(GpuSaoUpsamplePush { depth_sigma_rel });

/// The most levels of the depth pyramid: taps up to 2^(LOG_Q + 1 + 5) = 1024 pixels away
/// step down five levels (McGuire et al. 2012 use 5 as the coarsest level too).
pub const DEPTH_LEVELS: u32 = 6;

/// The depth pyramid's levels for a `width`×`height` frame: [`DEPTH_LEVELS`], or fewer where
/// the frame halves to one texel first (Vulkan mip sizes: halved, rounded down, at least 1).
pub fn depth_levels(width: u32, height: u32) -> u32 {
    (width.max(height).max(1).ilog2() + 1).min(DEPTH_LEVELS)
}

/// The SAO, blur and upsampling pipelines.
pub struct Sao {
    depth_first: ComputePipeline,
    depth: ComputePipeline,
    sao: ComputePipeline,
    blur: ComputePipeline,
    upsample: ComputePipeline,
    push: GpuSaoPush,
}

impl Sao {
    pub fn new(ctx: &Context, push: GpuSaoPush) -> Result<Self, VkError> {
        let depth_first = ctx.compute_pipeline(
            "sao_depth.comp",
            None,
            &crate::spec_constants![FIRST = true],
        )?;
        let depth = ctx.compute_pipeline(
            "sao_depth.comp",
            None,
            &crate::spec_constants![FIRST = false],
        )?;
        let sao = ctx.compute_pipeline("sao.comp", PushLayout::of::<GpuSaoPush>(), &[])?;
        let blur =
            ctx.compute_pipeline("sao_blur.comp", PushLayout::of::<GpuSaoBlurPush>(), &[])?;
        let upsample = ctx.compute_pipeline(
            "sao_upsample.comp",
            PushLayout::of::<GpuSaoUpsamplePush>(),
            &[],
        )?;
        Ok(Self {
            depth_first,
            depth,
            sao,
            blur,
            upsample,
            push,
        })
    }

    /// Declares `sao_depth[k]` for each level; returns the pyramid (RGBA32F, the frame's size
    /// with [`depth_levels`] mips: normal in xyz, view depth in w).
    fn add_depth_pyramid(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
    ) -> ImageHandle {
        let c = Shader::Compute;
        let levels = depth_levels(i.width, i.height);
        let pyramid = g.create_image(
            ImageDesc::new_2d(
                "sao depth pyramid",
                vk::Format::R32G32B32A32_SFLOAT,
                i.width,
                i.height,
            )
            .with_mips(levels),
        );
        for k in 0..levels {
            let (w, h) = ((i.width >> k).max(1), (i.height >> k).max(1));
            let groups = (w.div_ceil(8), h.div_ceil(8));
            let pass = g
                .add_pass(&format!("sao_depth[{k}]"))
                .bind(0, i.frame, Access::StorageRead(c))
                .bind_sampled(1, i.depth, sampler, c)
                .bind_sampled(2, i.normal, sampler, c);
            // Level 0 never reads the finer binding; the depth buffer fills it.
            let (pass, pipe) = if k == 0 {
                let pipe = *self.depth_first;
                (
                    pass.pipeline(&pipe).bind_sampled(3, i.depth, sampler, c),
                    pipe,
                )
            } else {
                let pipe = *self.depth;
                let finer = Access::Sampled(c);
                (
                    pass.pipeline(&pipe)
                        .bind_mip(3, pyramid, k - 1, finer, Some(sampler)),
                    pipe,
                )
            };
            pass.bind_mip(4, pyramid, k, Access::StorageWrite(c), None)
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
        }
        pyramid
    }

    /// Declares `sao_depth[k]`, `sao`, the horizontal and vertical `sao_blur` and
    /// `sao_upsample`; returns the AO term at the frame's size (R32F).
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
    ) -> ImageHandle {
        let pyramid = self.add_depth_pyramid(g, i, sampler);
        let (w, h) = (i.width.div_ceil(2), i.height.div_ceil(2));
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let c = Shader::Compute;
        let ao_image = |g: &mut RenderGraph, name: &str| {
            g.create_image(ImageDesc::new_2d(name, vk::Format::R32_SFLOAT, w, h))
        };
        let raw = ao_image(g, "sao");
        let pipe = *self.sao;
        let push = GpuSaoPush {
            depth_levels: depth_levels(i.width, i.height),
            ..self.push
        };
        let mut pass = g
            .add_pass("sao")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c));
        // One binding per level (see `pyramid_texel` in the shader); the bindings past the
        // pyramid's levels take its coarsest and are never read.
        for k in 0..DEPTH_LEVELS {
            let level = k.min(push.depth_levels - 1);
            pass = pass.bind_mip(1 + k, pyramid, level, Access::Sampled(c), Some(sampler));
        }
        pass.bind(7, raw, Access::StorageWrite(c))
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
        let full = g.create_image(ImageDesc::new_2d(
            "sao upsampled",
            vk::Format::R32_SFLOAT,
            i.width,
            i.height,
        ));
        let pipe = *self.upsample;
        let push = GpuSaoUpsamplePush {
            depth_sigma_rel: BLUR_DEPTH_SIGMA_REL,
        };
        let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
        g.add_pass("sao_upsample")
            .pipeline(&pipe)
            .bind_mip(0, pyramid, 0, Access::Sampled(c), Some(sampler))
            .bind_sampled(1, current, sampler, c)
            .bind(2, full, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        full
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
        crate::vk::check_push_against(
            &["sao_upsample.comp"],
            PushLayout::of::<GpuSaoUpsamplePush>(),
        )
        .unwrap();
    }

    /// The spiral takes the settings' tap count (`gi.sao_taps`, `--sao-taps`).
    #[test]
    fn the_push_takes_the_tap_count() {
        for taps in [1, 8, 16, 256] {
            let s = SaoSettings {
                taps,
                ..Default::default()
            };
            assert_eq!(GpuSaoPush::new(&s, 60.0, (64, 64), 0).taps, taps);
        }
    }

    /// Six levels at any frame of 32 pixels or more a side; a 16×8 frame halves to one texel
    /// after five (16, 8, 4, 2, 1), a single pixel has one.
    #[test]
    fn the_depth_pyramid_stops_at_one_texel() {
        assert_eq!(depth_levels(1920, 1080), 6);
        assert_eq!(depth_levels(64, 64), 6);
        assert_eq!(depth_levels(16, 8), 5);
        assert_eq!(depth_levels(1, 1), 1);
    }
}

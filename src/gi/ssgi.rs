//! `--gi ssgi`: screen-space diffuse global illumination after Oetke 2017 (§2.3, §5.1–5.3,
//! after Soler, Hoel and Rousselle 2010), with unlimited bounces by feedback (§2.3, §7.5).
//! No voxels: the frame's own G-buffer and direct light are the scene.
//!
//! Passes (one file per shader family, `glsl/ssgi_*.comp`):
//! - `ssgi_input`: level 0 of three pyramids at the frame's size: world position with view
//!   depth, normal, and the lit colour (direct light with emission, plus the previous frame's
//!   indirect light reprojected with the previous camera when feedback is on);
//! - `ssgi_mip[k]`: level k from k − 1, colour by box average, position and normal by the
//!   voting filter (or the first non-sky child, `--ssgi-mips fast`);
//! - `ssgi_gather[k]`, from the coarsest level down to the GI resolution (level
//!   log2(divisor)): Eq. 2.12 with the patch area of Eq. 2.10 over each level's ring, plus the
//!   coarser result joint-bilaterally upsampled;
//! - `ssgi_reflect*` (scenes with Phong or GGX materials, unless `--ssr off`): screen-space
//!   reflection rays, see [`super::ssgi_reflect`];
//! - `ssgi_upsample`: joint bilateral upsampling to the frame, blended with the history
//!   `ssgi_input` reprojected (τ = `history_weight`), the history for the next
//!   frame's feedback, and the camera it was seen with; Phong and GGX pixels add their
//!   specular indirect light (Eq. 2.19).
//!
//! The output is the indirect irradiance the shared `gi_filter` and `gi_composite` read (SAO
//! multiplies in when on). Limits the thesis names apply: no visibility (light leaks through
//! occluders), nothing off-screen contributes, and the lit colour includes the direct
//! specular light of Phong and GGX pixels (the thesis feeds the diffuse part only).

use super::gi_common::GiShared;
use super::ssgi_brdf_lut::BrdfLut;
use super::ssgi_reflect::{Ssr, SsrInputs};
use super::{GiInputs, GiMethodPasses, GiOutput, GiTarget, SsgiMips, SsgiSettings};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Buffer, ComputePipeline, Context, Image, ImageDesc, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::Ordering;

/// The gather's ring radius R in texels of each level (Oetke 2017 §5.2: 40 px).
pub const RING_RADIUS_TEXELS: f32 = 40.0;
/// The finest gathered level's inner radius: the texel itself is left out (its own surface
/// sends nothing to it; the thesis uses 4 px).
const INNER_RADIUS_TEXELS: f32 = 1.0;
/// Turns of the sample spiral (Oetke 2017 §5.2: 19).
const SPIRAL_TURNS: f32 = 19.0;

/// Push constants of `glsl/ssgi_input.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSsgiInputPush {
    feedback_max_w_m2: f32,
}
crate::push_constants!(GpuSsgiInputPush { feedback_max_w_m2 });

/// Push constants of `glsl/ssgi_gather.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSsgiGatherPush {
    ds_factor: f32,
    radius_texels: f32,
    inner_texels: f32,
    samples: u32,
    seed: u32,
    spiral_turns: f32,
}
crate::push_constants!(GpuSsgiGatherPush {
    ds_factor,
    radius_texels,
    inner_texels,
    samples,
    seed,
    spiral_turns
});

/// Push constants of `glsl/ssgi_upsample.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSsgiUpsamplePush {
    scale: f32,
    history_weight: f32,
}
crate::push_constants!(GpuSsgiUpsamplePush {
    scale,
    history_weight
});

/// The pyramid levels of a `width`×`height` frame: the GI resolution's level (log2 of the
/// divisor, at most the coarsest) and the coarsest level, whose ring of R·2^k pixels covers
/// the frame's diagonal (Oetke 2017 §5.2: max_mip = ceil(log2(diagonal / R))).
pub fn levels(width: u32, height: u32, divisor: u32) -> (u32, u32) {
    let diagonal_px = ((width as f32).powi(2) + (height as f32).powi(2)).sqrt();
    let coarsest = (diagonal_px / RING_RADIUS_TEXELS).log2().ceil().max(0.0) as u32;
    let base = divisor.max(1).ilog2();
    let coarsest = coarsest.max(base);
    (base, coarsest)
}

/// The size of pyramid level `k` of a `width`×`height` frame (halved, rounded up).
pub fn level_size(width: u32, height: u32, k: u32) -> (u32, u32) {
    let mut s = (width, height);
    for _ in 0..k {
        s = (s.0.div_ceil(2), s.1.div_ceil(2));
    }
    s
}

/// Eq. 2.10's constant for level `k`: the area per squared view depth of a level-k texel
/// facing the camera on the axis, 4 tan(f_h/2) tan(f_v/2) · 4^k / (W·H).
pub fn ds_factor(fov_y_deg: f32, width: u32, height: u32, k: u32) -> f32 {
    let tan_v = (fov_y_deg.to_radians() * 0.5).tan();
    let tan_h = tan_v * width as f32 / height as f32;
    4.0 * tan_h * tan_v * 4f32.powi(k as i32) / (width as f32 * height as f32)
}

/// The screen-space GI's pipelines and its persistent history.
pub struct Ssgi {
    settings: SsgiSettings,
    input: ComputePipeline,
    mip: ComputePipeline,
    gather: ComputePipeline,
    gather_top: ComputePipeline,
    upsample: ComputePipeline,
    /// Last frame's irradiance and clip w per pixel (the frame's size), for the feedback.
    history: Image,
    /// The camera (`view_proj`) the history was seen with.
    prev_camera: Buffer,
    /// The split-sum table (scenes with GGX materials).
    brdf_lut: Option<BrdfLut>,
    /// Screen-space reflections (scenes with Phong or GGX materials, `settings.ssr`).
    ssr: Option<Ssr>,
    fov_y_deg: f32,
}

/// One pyramid level's images.
#[derive(Clone, Copy)]
struct Level {
    pos: ImageHandle,
    nrm: ImageHandle,
    color: ImageHandle,
    size: (u32, u32),
}

impl Ssgi {
    pub fn new(
        ctx: &Context,
        settings: SsgiSettings,
        target: &GiTarget<'_>,
    ) -> Result<Self, VkError> {
        let input = ctx.compute_pipeline(
            "ssgi_input.comp",
            PushLayout::of::<GpuSsgiInputPush>(),
            &crate::spec_constants![FEEDBACK = settings.feedback],
        )?;
        let mip = ctx.compute_pipeline(
            "ssgi_mip.comp",
            None,
            &crate::spec_constants![VOTING = settings.mips == SsgiMips::Voting],
        )?;
        let gather = ctx.compute_pipeline(
            "ssgi_gather.comp",
            PushLayout::of::<GpuSsgiGatherPush>(),
            &crate::spec_constants![HAS_COARSER = true],
        )?;
        let gather_top = ctx.compute_pipeline(
            "ssgi_gather.comp",
            PushLayout::of::<GpuSsgiGatherPush>(),
            &crate::spec_constants![HAS_COARSER = false],
        )?;
        let glossy = target.has_phong || target.scene.has_ggx();
        let ssr = (settings.ssr && glossy)
            .then(|| Ssr::new(ctx, target, settings.history_weight, settings.ssr_rays))
            .transpose()?;
        let upsample = ctx.compute_pipeline(
            "ssgi_upsample.comp",
            PushLayout::of::<GpuSsgiUpsamplePush>(),
            &crate::spec_constants![
                HAS_PHONG = target.has_phong,
                HAS_GGX = target.scene.has_ggx(),
                SSR = ssr.is_some(),
            ],
        )?;
        let (history, prev_camera) = Self::create_history(ctx, target.size)?;
        // The split-sum table, for scenes with GGX materials only.
        let brdf_lut = target
            .scene
            .has_ggx()
            .then(|| BrdfLut::new(ctx))
            .transpose()?;
        Ok(Self {
            settings,
            input,
            mip,
            gather,
            gather_top,
            upsample,
            history,
            prev_camera,
            brdf_lut,
            ssr,
            fov_y_deg: target.scene.camera.fov_y_deg,
        })
    }

    /// The history image of a `w`×`h` frame (also counted by the renderer's memory check).
    pub fn history_desc((w, h): (u32, u32)) -> ImageDesc {
        ImageDesc::new_2d("ssgi history", vk::Format::R32G32B32A32_SFLOAT, w, h)
            .with_usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED)
    }

    /// The history image, cleared (clip w 0: no pixel has a history yet), and the previous
    /// camera's buffer.
    fn create_history(ctx: &Context, (w, h): (u32, u32)) -> Result<(Image, Buffer), VkError> {
        let history = ctx.create_zeroed_image(
            &Self::history_desc((w, h)),
            Access::Sampled(Shader::Compute).info().layout,
        )?;
        let camera = ctx.upload_buffer(
            "ssgi previous camera",
            &[0u8; 64],
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok((history, camera))
    }

    /// Declares `ssgi_input` and the `ssgi_mip` levels up to `coarsest`; returns the levels
    /// and the reprojected history (irradiance, weight) at the frame's size.
    fn add_pyramid(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        shared: &GiShared,
        (history, prev_camera): (ImageHandle, BufferHandle),
        coarsest: u32,
    ) -> (Vec<Level>, ImageHandle) {
        let c = Shader::Compute;
        let s = shared.sampler;
        let level_images = |g: &mut RenderGraph, k: u32| {
            let size = level_size(i.width, i.height, k);
            let img = |g: &mut RenderGraph, what: &str, format| {
                g.create_image(ImageDesc::new_2d(
                    &format!("ssgi {what} [{k}]"),
                    format,
                    size.0,
                    size.1,
                ))
            };
            Level {
                pos: img(g, "position", vk::Format::R32G32B32A32_SFLOAT),
                nrm: img(g, "normal", vk::Format::R16G16B16A16_SFLOAT),
                color: img(g, "colour", vk::Format::R32G32B32A32_SFLOAT),
                size,
            }
        };
        let l0 = level_images(g, 0);
        let reprojected = g.create_image(ImageDesc::new_2d(
            "ssgi reprojected history",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        let pipe = *self.input;
        let push = GpuSsgiInputPush {
            feedback_max_w_m2: self.settings.feedback_max_w_m2,
        };
        let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
        g.add_pass("ssgi_input")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.depth, s, c)
            .bind_sampled(2, i.normal, s, c)
            .bind_sampled(3, i.albedo, s, c)
            .bind_sampled(4, i.direct, s, c)
            .bind_sampled(5, history, s, c)
            .bind(6, prev_camera, Access::StorageRead(c))
            .bind(7, l0.pos, Access::StorageWrite(c))
            .bind(8, l0.nrm, Access::StorageWrite(c))
            .bind(9, l0.color, Access::StorageWrite(c))
            .bind(10, reprojected, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        let mut levels = vec![l0];
        for k in 1..=coarsest {
            let (prev, next) = (levels[k as usize - 1], level_images(g, k));
            let pipe = *self.mip;
            let groups = (next.size.0.div_ceil(8), next.size.1.div_ceil(8));
            g.add_pass(&format!("ssgi_mip[{k}]"))
                .pipeline(&pipe)
                .bind_sampled(0, prev.pos, s, c)
                .bind_sampled(1, prev.nrm, s, c)
                .bind_sampled(2, prev.color, s, c)
                .bind(3, next.pos, Access::StorageWrite(c))
                .bind(4, next.nrm, Access::StorageWrite(c))
                .bind(5, next.color, Access::StorageWrite(c))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
            levels.push(next);
        }
        (levels, reprojected)
    }

    /// Declares `ssgi_gather[k]` from `coarsest` down to `base`; returns level `base`'s
    /// irradiance.
    fn add_gathers(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        shared: &GiShared,
        levels: &[Level],
        (base, coarsest): (u32, u32),
    ) -> ImageHandle {
        let c = Shader::Compute;
        let s = shared.sampler;
        let mut coarser: Option<(ImageHandle, Level)> = None;
        for k in (base..=coarsest).rev() {
            let l = levels[k as usize];
            let out = g.create_image(ImageDesc::new_2d(
                &format!("ssgi irradiance [{k}]"),
                vk::Format::R32G32B32A32_SFLOAT,
                l.size.0,
                l.size.1,
            ));
            let push = GpuSsgiGatherPush {
                ds_factor: ds_factor(self.fov_y_deg, i.width, i.height, k),
                radius_texels: RING_RADIUS_TEXELS,
                inner_texels: if k == base {
                    INNER_RADIUS_TEXELS
                } else {
                    RING_RADIUS_TEXELS * 0.5
                },
                samples: self.settings.samples,
                seed: 0,
                spiral_turns: SPIRAL_TURNS,
            };
            let pipe = if coarser.is_some() {
                *self.gather
            } else {
                *self.gather_top
            };
            // The top level never reads its coarser bindings; its own position fills them.
            let (cv, cl) = coarser.unwrap_or((l.pos, l));
            let frames = shared.frames.clone();
            let seed0 = shared.push.seed;
            let groups = (l.size.0.div_ceil(8), l.size.1.div_ceil(8));
            g.add_pass(&format!("ssgi_gather[{k}]"))
                .pipeline(&pipe)
                .bind(0, i.frame, Access::StorageRead(c))
                .bind_sampled(1, l.pos, s, c)
                .bind_sampled(2, l.nrm, s, c)
                .bind_sampled(3, l.color, s, c)
                .bind_sampled(4, cv, s, c)
                .bind_sampled(5, cl.pos, s, c)
                .bind_sampled(6, cl.nrm, s, c)
                .bind(7, out, Access::StorageWrite(c))
                .record(move |ctx| {
                    // A new spiral rotation every frame (the feedback averages them).
                    let frame = frames.load(Ordering::SeqCst);
                    let push = GpuSsgiGatherPush {
                        seed: seed0.wrapping_add(frame.wrapping_mul(7919)),
                        ..push
                    };
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
            coarser = Some((out, l));
        }
        coarser.map_or(levels[base as usize].pos, |(img, _)| img)
    }
}

impl GiMethodPasses for Ssgi {
    fn add_passes(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> GiOutput {
        let c = Shader::Compute;
        let (base, coarsest) = levels(i.width, i.height, self.settings.resolution.divisor());
        let history = g.import_image(&self.history, Access::Sampled(c));
        let prev_camera = g.import_buffer(&self.prev_camera, Access::StorageRead(c));
        let (levels, reprojected) =
            self.add_pyramid(g, i, shared, (history, prev_camera), coarsest);
        let coarse = self.add_gathers(g, i, shared, &levels, (base, coarsest));
        let (lb, l0) = (levels[base as usize], levels[0]);
        let indirect = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        let s = shared.sampler;
        // Without Phong materials the shader never reads its specular binding; albedo fills it.
        let specular = i.specular.unwrap_or(i.albedo);
        let lut = self
            .brdf_lut
            .as_ref()
            .map(|l| g.import_image(&l.image, Access::Sampled(c)));
        // Without reflections the shader never reads their binding; albedo fills it.
        let ssr = match (&self.ssr, i.specular) {
            (Some(ssr), Some(specular)) => {
                let inputs = SsrInputs {
                    fine_pos: l0.pos,
                    fine_nrm: l0.nrm,
                    lit_color: l0.color,
                    specular,
                    gi_history: history,
                    prev_camera,
                    brdf_lut: lut,
                };
                ssr.add_passes(g, i, s, &inputs)
            }
            _ => i.albedo,
        };
        // Without GGX materials the shader never reads the table; albedo fills it.
        let lut = lut.unwrap_or(i.albedo);
        let pipe = *self.upsample;
        let push = GpuSsgiUpsamplePush {
            scale: (1u32 << base) as f32,
            history_weight: self.settings.history_weight,
        };
        let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
        g.add_pass("ssgi_upsample")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, coarse, s, c)
            .bind_sampled(2, lb.pos, s, c)
            .bind_sampled(3, lb.nrm, s, c)
            .bind_sampled(4, l0.pos, s, c)
            .bind_sampled(5, l0.nrm, s, c)
            .bind_sampled(6, i.albedo, s, c)
            .bind_sampled(7, specular, s, c)
            .bind(8, indirect, Access::StorageWrite(c))
            .bind(9, history, Access::StorageWrite(c))
            .bind(10, prev_camera, Access::StorageWrite(c))
            .bind_sampled(11, i.normal, s, c)
            .bind_sampled(12, lut, s, c)
            .bind_sampled(13, reprojected, s, c)
            .bind_sampled(14, ssr, s, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        indirect.into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_match_glsl() {
        let check = |shader: &str, push| {
            crate::vk::check_push_against(&[shader], push).unwrap_or_else(|e| panic!("{e}"))
        };
        check("ssgi_input.comp", PushLayout::of::<GpuSsgiInputPush>());
        check("ssgi_gather.comp", PushLayout::of::<GpuSsgiGatherPush>());
        check(
            "ssgi_upsample.comp",
            PushLayout::of::<GpuSsgiUpsamplePush>(),
        );
    }

    /// 1920×1080 as in Oetke 2017 §5.2: the coarsest level is 6 (40·2⁶ = 2560 px ≥ the
    /// 2203 px diagonal, 40·2⁵ = 1280 px is not); a 128² frame needs 3 (181 px diagonal).
    #[test]
    fn levels_cover_the_diagonal() {
        assert_eq!(levels(1920, 1080, 2), (1, 6));
        assert_eq!(levels(128, 128, 1), (0, 3));
        assert_eq!(levels(128, 128, 4), (2, 3));
        assert_eq!(
            levels(16, 16, 8),
            (3, 3),
            "the GI level is never above the coarsest"
        );
        assert_eq!(level_size(129, 64, 2), (33, 16));
    }

    /// Eq. 2.10 facing the camera at 1 m on the axis: the frame's W·H pixels tile the
    /// 2 tan(f_h/2) × 2 tan(f_v/2) image plane, a level-k texel covers 4^k of them.
    #[test]
    fn patch_area_tiles_the_image_plane() {
        let (w, h) = (200, 100);
        let plane_m2 = 4.0 * (0.5f32).tan() * 2.0 * (0.5f32).tan();
        let total = ds_factor(57.29578, w, h, 0) * (w * h) as f32;
        assert!(
            (total - plane_m2).abs() < 1e-4 * plane_m2,
            "{total} vs {plane_m2}"
        );
        assert!((ds_factor(57.29578, w, h, 2) / ds_factor(57.29578, w, h, 0) - 16.0).abs() < 1e-3);
    }
}

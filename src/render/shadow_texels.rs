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
    /// 1: d_i with the projective factor cos α_i / cos α_s; 0: its perspective part only.
    projective: u32,
}

crate::push_constants!(GpuShadowTexelsPush {
    pixel_scale,
    projective
});

pub struct ShadowTexelsPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
    /// Pixels per meter at one meter of view depth: height / (2 tan(fov_y / 2)).
    pixel_scale: f32,
    /// Whether d_i includes the projective factor (`--debug shadow-texels`) or not
    /// (`--debug shadow-texels-perspective`).
    projective: bool,
}

impl ShadowTexelsPass {
    pub fn new(
        ctx: &Context,
        sampler: vk::Sampler,
        camera: &crate::scene::Camera,
        height: u32,
        projective: bool,
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
            projective,
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
            projective: u32::from(self.projective),
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

/// `--shadow-resolution auto` ("model only what a scene requires"): the smallest shadow-map
/// resolution that keeps the predicted on-screen texel d_i at most one pixel for
/// [`AUTO_QUANTILE`] of the lit pixels of the view. One probe frame of this view at
/// [`AUTO_PROBE_RESOLUTION`] gives each lit pixel's d_i. Every map's texel footprint is its
/// window (or frustum) width over its resolution — perspective, orthographic, paraboloid, and
/// cascades up to their few margin texels — so at resolution R a pixel's texel is
/// d_i·R_probe/R, and the quantile q of d_i at the probe needs R ≥ q·R_probe.
pub const AUTO_PROBE_RESOLUTION: u32 = 1024;
/// Share of the lit pixels whose texel must be at most a pixel: not all of them, since d_i
/// grows without bound where the light grazes a surface (cos α_s → 0).
pub const AUTO_QUANTILE: f64 = 0.95;
/// The smallest map `auto` picks (a view without shadowed lit pixels gets this one).
pub const AUTO_MIN_RESOLUTION: u32 = 64;

/// What `--shadow-resolution auto` chose, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoShadowResolution {
    /// The chosen texels per side.
    pub resolution: u32,
    /// The [`AUTO_QUANTILE`] of the lit pixels' d_i at the probe resolution, pixels.
    pub quantile_px_at_probe: f32,
    pub probe_resolution: u32,
}

/// The smallest power of two R in [[`AUTO_MIN_RESOLUTION`], `max`] with
/// quantile(d_i)·probe/R ≤ 1 (`max` if none is), from the lit pixels' d_i at `probe`.
pub fn pick_shadow_resolution(d_px: &[f32], probe: u32, max: u32) -> AutoShadowResolution {
    let mut d: Vec<f32> = d_px.iter().copied().filter(|&x| x > 0.0).collect();
    d.sort_by(f32::total_cmp);
    let q = match d.len() {
        0 => 0.0,
        n => d[((AUTO_QUANTILE * n as f64).ceil() as usize).clamp(1, n) - 1],
    };
    let need = (f64::from(q) * f64::from(probe)).ceil().max(1.0) as u32;
    let max = max.max(AUTO_MIN_RESOLUTION);
    let resolution = need
        .checked_next_power_of_two()
        .unwrap_or(max)
        .clamp(AUTO_MIN_RESOLUTION, max);
    AutoShadowResolution {
        resolution,
        quantile_px_at_probe: q,
        probe_resolution: probe,
    }
}

/// Resolves `settings.shadow.auto_resolution` for `scene`: one probe frame of the shadow-texel
/// view (direct light only; GI does not change the shadow views), then the settings with the
/// picked resolution.
pub fn resolve_auto_resolution(
    ctx: &Context,
    scene: &crate::scene::Scene,
    settings: &super::RenderSettings,
) -> Result<(super::RenderSettings, AutoShadowResolution), super::RenderError> {
    let max = crate::scene::shadow_range::SHADOW_RESOLUTION
        .max
        .min(ctx.info.max_image_dimension_2d);
    let probe_res = AUTO_PROBE_RESOLUTION.min(max);
    let mut probe = settings.clone();
    probe.shadow.auto_resolution = false;
    probe.shadow.resolution = probe_res;
    probe.gi = crate::gi::GiSettings::default();
    probe.post = Default::default();
    probe.debug = Some(crate::voxel::debug_view::DebugSettings {
        view: crate::voxel::debug_view::DebugView::ShadowTexelsPerspective,
        ..Default::default()
    });
    let value = super::render_image(ctx, scene, &probe)?.hdr;
    let d: Vec<f32> = value.data.iter().map(|p| p[0]).collect();
    let pick = pick_shadow_resolution(&d, probe_res, max);
    let mut out = settings.clone();
    out.shadow.auto_resolution = false;
    out.shadow.resolution = pick.resolution;
    Ok((out, pick))
}

#[cfg(test)]
mod auto_tests {
    use super::*;

    /// d_i halves when R doubles: a 95th percentile of 1.5 px at 1024² needs 1536 texels, so
    /// 2048²; of 0.3 px, 308 texels, so 512²; nothing lit needs nothing, so the minimum; and
    /// more than the device has is capped.
    #[test]
    fn the_pick_is_the_smallest_power_of_two_under_a_pixel() {
        let spread = |q95: f32| -> Vec<f32> {
            // 100 lit pixels: 95 at or below q95, 5 far above it (grazing), 20 unlit (0).
            let mut d: Vec<f32> = (1..=95).map(|i| q95 * i as f32 / 95.0).collect();
            d.extend([50.0; 5]);
            d.extend([0.0; 20]);
            d
        };
        let pick = |q95: f32| pick_shadow_resolution(&spread(q95), 1024, 8192);
        assert_eq!(pick(1.5).resolution, 2048);
        assert!((pick(1.5).quantile_px_at_probe - 1.5).abs() < 1e-6);
        assert_eq!(pick(0.3).resolution, 512);
        assert_eq!(pick(1.0).resolution, 1024);
        assert_eq!(pick(0.01).resolution, AUTO_MIN_RESOLUTION);
        assert_eq!(
            pick_shadow_resolution(&[0.0; 10], 1024, 8192).resolution,
            AUTO_MIN_RESOLUTION
        );
        assert_eq!(
            pick_shadow_resolution(&spread(40.0), 1024, 4096).resolution,
            4096
        );
        // At the pick, the quantile is at most one pixel: q·probe/R ≤ 1.
        for q in [0.05f32, 0.2, 0.7, 1.3, 3.9] {
            let p = pick(q);
            assert!(q * 1024.0 / p.resolution as f32 <= 1.0 + 1e-6, "{q}: {p:?}");
            if p.resolution > AUTO_MIN_RESOLUTION {
                assert!(
                    q * 1024.0 / (p.resolution / 2) as f32 > 1.0,
                    "{q}: {p:?} not smallest"
                );
            }
        }
    }
}

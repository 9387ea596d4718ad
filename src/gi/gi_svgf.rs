//! `gi_svgf_variance` and `gi_svgf`: spatiotemporal variance-guided filtering (Schied et al.
//! 2017 §4.2–4.4), the alternative to the geometry-aware filter (`gi.filter = "svgf"`). A
//! variance estimate (from the temporal moments, or spatially where a pixel has no history)
//! guides the luminance weight of `gi.filter_passes` à-trous iterations of 5×5 taps at
//! spacing 1, 2, 4, …, which filter the variance along. The shaders' headers give the
//! weights and how voxgi's differ from the paper's.

use super::gi_filter::PLANE_TOLERANCE;
use super::GiInputs;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};

/// Push constants of `glsl/gi_svgf_variance.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuVariancePush {
    plane_tolerance: f32,
}

crate::push_constants!(GpuVariancePush { plane_tolerance });

/// Push constants of `glsl/gi_svgf.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuAtrousPush {
    /// The taps' spacing, 2^i in iteration i.
    step_px: i32,
    plane_tolerance: f32,
    /// Glossy pixels: taps within the VPLs' interleaving tile skip the mirror-direction
    /// weight (`[1, 1]` for the other methods).
    tile_px: [i32; 2],
    /// 1 in the last iteration, which writes alpha 1 instead of the variance.
    last: i32,
}

crate::push_constants!(GpuAtrousPush {
    step_px,
    plane_tolerance,
    tile_px,
    last
});

/// SVGF's two pipelines.
pub struct GiSvgf {
    variance: ComputePipeline,
    atrous: ComputePipeline,
}

impl GiSvgf {
    /// `glossy`: the G-buffer has a lobe target (Phong or GGX materials), which the filter
    /// then reads. `temporal`: the indirect light is accumulated over frames (`gi_temporal`),
    /// and the variance comes from its moments.
    pub fn new(ctx: &Context, glossy: bool, temporal: bool) -> Result<Self, VkError> {
        Ok(Self {
            variance: ctx.compute_pipeline(
                "gi_svgf_variance.comp",
                PushLayout::of::<GpuVariancePush>(),
                &crate::spec_constants![GLOSSY = glossy, TEMPORAL = temporal],
            )?,
            atrous: ctx.compute_pipeline(
                "gi_svgf.comp",
                PushLayout::of::<GpuAtrousPush>(),
                &crate::spec_constants![GLOSSY = glossy],
            )?,
        })
    }

    /// Declares the variance estimate and `iterations` à-trous passes over `irradiance` (none
    /// when `iterations` is 0 or `on` is false); returns the filtered image. `tile` and
    /// `moments` as for [`super::gi_filter::GiFilter::add_passes`].
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        (on, iterations, tile): (bool, u32, [u32; 2]),
        irradiance: ImageHandle,
        moments: Option<ImageHandle>,
    ) -> ImageHandle {
        if !on || iterations == 0 {
            return irradiance;
        }
        let (w, h) = (i.width, i.height);
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let c = Shader::Compute;
        let lobes = i.specular.unwrap_or(i.normal);
        // Without temporal accumulation the shader never reads its binding 6; the normals
        // fill it.
        let moments = moments.unwrap_or(i.normal);
        let image = |g: &mut RenderGraph, name: &str| {
            g.create_image(ImageDesc::new_2d(
                name,
                vk::Format::R32G32B32A32_SFLOAT,
                w,
                h,
            ))
        };
        let estimate = image(g, "svgf variance");
        let vp = GpuVariancePush {
            plane_tolerance: PLANE_TOLERANCE,
        };
        let pipe = *self.variance;
        g.add_pass("gi_svgf_variance")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.normal, sampler, c)
            .bind_sampled(2, i.depth, sampler, c)
            .bind_sampled(3, irradiance, sampler, c)
            .bind(4, estimate, Access::StorageWrite(c))
            .bind_sampled(5, lobes, sampler, c)
            .bind_sampled(6, moments, sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&vp));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        let pipe = *self.atrous;
        let mut current = estimate;
        for it in 0..iterations {
            let out = image(g, &format!("svgf iteration {it}"));
            let ap = GpuAtrousPush {
                step_px: 1 << it,
                plane_tolerance: PLANE_TOLERANCE,
                tile_px: [tile[0].max(1) as i32, tile[1].max(1) as i32],
                last: i32::from(it + 1 == iterations),
            };
            g.add_pass(&format!("gi_svgf[{it}]"))
                .pipeline(&pipe)
                .bind(0, i.frame, Access::StorageRead(c))
                .bind_sampled(1, i.normal, sampler, c)
                .bind_sampled(2, i.depth, sampler, c)
                .bind_sampled(3, current, sampler, c)
                .bind(4, out, Access::StorageWrite(c))
                .bind_sampled(5, lobes, sampler, c)
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&ap));
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
        crate::vk::check_push_against(
            &["gi_svgf_variance.comp"],
            PushLayout::of::<GpuVariancePush>(),
        )
        .unwrap();
        crate::vk::check_push_against(&["gi_svgf.comp"], PushLayout::of::<GpuAtrousPush>())
            .unwrap();
    }
}

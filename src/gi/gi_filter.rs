//! `gi_filter`: the geometry-aware filter of the indirect irradiance (Herzog et al. 2010, as
//! Thiedemann 2010 uses it in ch. 7): a separable joint bilateral blur weighted by distance,
//! normal similarity and distance from the centre pixel's tangent plane, horizontal then
//! vertical, repeated. In scenes with Phong or GGX materials a pixel also averages only pixels
//! of its lobe kind, and a glossy one only those whose mirror directions lie within its lobe
//! (the shader's header).

use super::GiInputs;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};

/// Push constants of `glsl/gi_filter.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuFilterPush {
    direction: [i32; 2],
    radius: i32,
    plane_tolerance: f32,
    /// Glossy pixels: taps closer than this skip the mirror-direction weight (the VPLs'
    /// interleaving pattern side along the pass; 1 otherwise).
    tile_px: i32,
}

crate::push_constants!(GpuFilterPush {
    direction,
    radius,
    plane_tolerance,
    tile_px
});

/// A tap's tolerated distance from the centre's tangent plane, relative to the centre's
/// distance from the camera (SVGF's surface weight uses the same).
pub(super) const PLANE_TOLERANCE: f32 = 0.02;

/// The filter's pipeline.
pub struct GiFilter {
    pipeline: ComputePipeline,
}

impl GiFilter {
    /// `glossy`: the G-buffer has a lobe target (Phong or GGX materials), which the filter
    /// then reads. `variance_guided`: the indirect light is accumulated over frames
    /// (`gi_temporal`), and the filter steps back as the variance of its mean falls.
    pub fn new(ctx: &Context, glossy: bool, variance_guided: bool) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "gi_filter.comp",
            PushLayout::of::<GpuFilterPush>(),
            &crate::spec_constants![GLOSSY = glossy, VARIANCE_GUIDED = variance_guided],
        )?;
        Ok(Self { pipeline })
    }

    /// Declares `passes` horizontal + vertical pass pairs of radius `radius_px` over
    /// `irradiance` (none when either is 0); returns the filtered image. `tile` is the VPLs'
    /// interleaving pattern N×M (`[1, 1]` for the other methods): within it glossy pixels are
    /// averaged like Lambert ones, since each holds only one of the tile's VPL sets.
    /// `moments`: under temporal accumulation, `irradiance` holds the history length in its
    /// alpha and these images the moments (`gi_temporal`); the filter must then have been
    /// made `variance_guided`.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        sampler: vk::Sampler,
        (radius_px, passes, tile): (u32, u32, [u32; 2]),
        irradiance: ImageHandle,
        moments: Option<ImageHandle>,
    ) -> ImageHandle {
        let (w, h) = (i.width, i.height);
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let passes = if radius_px == 0 { 0 } else { passes };
        let c = Shader::Compute;
        let pipe = *self.pipeline;
        // Without a lobe target the shader never reads its binding 5; the normals fill it.
        let lobes = i.specular.unwrap_or(i.normal);
        // Without temporal accumulation the shader never reads bindings 6 and 7; the normals
        // fill them.
        let (accumulated, moments) = match moments {
            Some(m) => (irradiance, m),
            None => (i.normal, i.normal),
        };
        let mut current = irradiance;
        for p in 0..passes {
            for (axis, dir, tile_px) in [("h", [1, 0], tile[0]), ("v", [0, 1], tile[1])] {
                let out = g.create_image(ImageDesc::new_2d(
                    &format!("filtered irradiance {p}{axis}"),
                    vk::Format::R32G32B32A32_SFLOAT,
                    w,
                    h,
                ));
                let fp = GpuFilterPush {
                    direction: dir,
                    radius: radius_px as i32,
                    plane_tolerance: PLANE_TOLERANCE,
                    tile_px: tile_px.max(1) as i32,
                };
                g.add_pass(&format!("gi_filter[{p}{axis}]"))
                    .pipeline(&pipe)
                    .bind(0, i.frame, Access::StorageRead(c))
                    .bind_sampled(1, i.normal, sampler, c)
                    .bind_sampled(2, i.depth, sampler, c)
                    .bind_sampled(3, current, sampler, c)
                    .bind(4, out, Access::StorageWrite(c))
                    .bind_sampled(5, lobes, sampler, c)
                    .bind_sampled(6, accumulated, sampler, c)
                    .bind_sampled(7, moments, sampler, c)
                    .record(move |ctx| {
                        ctx.bind(&pipe);
                        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&fp));
                        ctx.cmd.dispatch(groups.0, groups.1, 1);
                    });
                current = out;
            }
        }
        current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_match_glsl() {
        crate::vk::check_push_against(&["gi_filter.comp"], PushLayout::of::<GpuFilterPush>())
            .unwrap();
    }
}

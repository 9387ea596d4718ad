//! `stereo_pack`: the two eyes' tone-mapped images packed into one (`glsl/stereo_pack.comp`):
//! an anaglyph or a spatial packing, chosen by [`StereoMode`].
//!
//! Anaglyphs are computed in **linear** RGB: the pass decodes the eyes' sRGB values, applies
//! the mode's two 3×3 matrices, clamps and encodes again. Dubois 2001 derives his matrices from
//! the display's linear RGB primaries and the filters' spectral transmissions, so they are
//! defined on linear values; the simple luminance/channel matrices (true, gray, color,
//! half-color) are applied the same way so that every anaglyph is one matrix product on the
//! same data (for the color mode, a pure channel selection, the result is the same either way).
//! Spatial packings copy the eyes' texels unchanged.

use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, VkError};

/// How a stereo pair is packed into one image. The left eye is in the red channel of every
/// anaglyph (red-cyan glasses, red filter on the left eye), left (or top, or the even rows,
/// columns and checkerboard squares whose x + y is even) in the spatial packings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StereoMode {
    /// Red = left luminance, blue = right luminance (dark, no colour).
    AnaglyphTrue,
    /// Red = left luminance, green and blue = right luminance.
    AnaglyphGray,
    /// Red from the left eye, green and blue from the right.
    AnaglyphColor,
    /// Red = left luminance, green and blue from the right (less retinal rivalry than color).
    AnaglyphHalfColor,
    /// Dubois's least-squares red-cyan projection (the optimized anaglyph).
    AnaglyphDubois,
    /// Each eye squeezed to half the width: left eye in the left half.
    SideBySide,
    /// Each eye at the full --width, left eye left: the image is twice as wide.
    SideBySideFull,
    /// Each eye squeezed to half the height: left eye on top.
    TopBottom,
    /// Even rows (0, 2, …) from the left eye, odd rows from the right.
    RowInterleaved,
    /// Even columns from the left eye, odd columns from the right.
    ColumnInterleaved,
    /// Texels with even x + y from the left eye, the others from the right.
    Checkerboard,
}

/// A 3×3 matrix by rows: output channel i = row i · input RGB.
pub type Rows3 = [[f32; 3]; 3];

/// Rec. 601 luma weights, the luminance of the classic anaglyph definitions.
const LUMA: [f32; 3] = [0.299, 0.587, 0.114];
const ZERO: [f32; 3] = [0.0; 3];

impl StereoMode {
    /// The anaglyph's (left, right) matrices in linear RGB, `None` for spatial packings.
    ///
    /// True, gray, color and half-color are the classic definitions (e.g. Wimmer 2004,
    /// "Anaglyph methods comparison", Stereoscopic Player): luminance or channels of each eye
    /// routed to red (left) and green/blue (right). Dubois's red-cyan least-squares matrices are
    /// from Dubois 2001, "A projection method to generate anaglyph stereo images" (ICASSP 2001),
    /// with the red-cyan numbers as published on his anaglyph web page (E. Dubois, University
    /// of Ottawa, "Least squares projection anaglyphs", red-cyan for Roscolux filters).
    pub fn anaglyph_matrices(self) -> Option<(Rows3, Rows3)> {
        let one = |i: usize| {
            let mut r = ZERO;
            r[i] = 1.0;
            r
        };
        Some(match self {
            StereoMode::AnaglyphTrue => ([LUMA, ZERO, ZERO], [ZERO, ZERO, LUMA]),
            StereoMode::AnaglyphGray => ([LUMA, ZERO, ZERO], [ZERO, LUMA, LUMA]),
            StereoMode::AnaglyphColor => ([one(0), ZERO, ZERO], [ZERO, one(1), one(2)]),
            StereoMode::AnaglyphHalfColor => ([LUMA, ZERO, ZERO], [ZERO, one(1), one(2)]),
            StereoMode::AnaglyphDubois => (
                [
                    [0.437, 0.449, 0.164],
                    [-0.062, -0.062, -0.024],
                    [-0.048, -0.050, -0.017],
                ],
                [
                    [-0.011, -0.032, -0.007],
                    [0.377, 0.761, 0.009],
                    [-0.026, -0.093, 1.234],
                ],
            ),
            _ => return None,
        })
    }

    /// `stereo_pack.comp`'s mode number (all anaglyphs are 0: the matrices tell them apart).
    pub fn shader_id(self) -> u32 {
        match self {
            StereoMode::AnaglyphTrue
            | StereoMode::AnaglyphGray
            | StereoMode::AnaglyphColor
            | StereoMode::AnaglyphHalfColor
            | StereoMode::AnaglyphDubois => 0,
            StereoMode::SideBySide => 1,
            StereoMode::SideBySideFull => 2,
            StereoMode::TopBottom => 3,
            StereoMode::RowInterleaved => 4,
            StereoMode::ColumnInterleaved => 5,
            StereoMode::Checkerboard => 6,
        }
    }

    /// The mode's name on the command line (`anaglyph-dubois`, `side-by-side-full`, …).
    pub fn name(self) -> String {
        clap::ValueEnum::to_possible_value(&self)
            .map(|v| v.get_name().to_owned())
            .unwrap_or_default()
    }

    /// The packed image's size for eyes of `(w, h)`: twice as wide for side-by-side-full, the
    /// eyes' size otherwise.
    pub fn packed_size(self, (w, h): (u32, u32)) -> (u32, u32) {
        match self {
            StereoMode::SideBySideFull => (2 * w, h),
            _ => (w, h),
        }
    }
}

/// Push constants of `stereo_pack.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuStereoPackPush {
    pub left_rows: [[f32; 4]; 3],
    pub right_rows: [[f32; 4]; 3],
    /// [`StereoMode::shader_id`].
    pub mode: u32,
    pub eye_width: u32,
    pub eye_height: u32,
}

crate::push_constants!(GpuStereoPackPush {
    left_rows,
    right_rows,
    mode,
    eye_width,
    eye_height
});

impl GpuStereoPackPush {
    pub fn new(mode: StereoMode, (eye_width, eye_height): (u32, u32)) -> Self {
        let pad = |m: Rows3| m.map(|[a, b, c]| [a, b, c, 0.0]);
        let (l, r) = mode.anaglyph_matrices().unwrap_or(([ZERO; 3], [ZERO; 3]));
        Self {
            left_rows: pad(l),
            right_rows: pad(r),
            mode: mode.shader_id(),
            eye_width,
            eye_height,
        }
    }
}

pub struct StereoPackPass {
    pipeline: ComputePipeline,
    sampler: vk::Sampler,
}

impl StereoPackPass {
    /// `sampler`: how the eyes are read (nearest: the shader fetches texels).
    pub fn new(ctx: &Context, sampler: vk::Sampler) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "stereo_pack.comp",
            crate::vk::PushLayout::of::<GpuStereoPackPush>(),
            &[],
        )?;
        Ok(Self { pipeline, sampler })
    }

    /// Declares the pass over two eye images of `eye_size`; returns the packed image (RGBA8
    /// UNORM holding sRGB values) of [`StereoMode::packed_size`].
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        (left, right): (ImageHandle, ImageHandle),
        mode: StereoMode,
        eye_size: (u32, u32),
    ) -> ImageHandle {
        let (w, h) = mode.packed_size(eye_size);
        let packed = g.create_image(ImageDesc::new_2d(
            "stereo packed",
            vk::Format::R8G8B8A8_UNORM,
            w,
            h,
        ));
        let pipe = *self.pipeline;
        let push = GpuStereoPackPush::new(mode, eye_size);
        g.add_pass("stereo_pack")
            .pipeline(&pipe)
            .bind_sampled(0, left, self.sampler, Shader::Compute)
            .bind_sampled(1, right, self.sampler, Shader::Compute)
            .bind(2, packed, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            });
        packed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_block_matches_the_shader() {
        crate::vk::check_push_against(
            &["stereo_pack.comp"],
            crate::vk::PushLayout::of::<GpuStereoPackPush>(),
        )
        .expect("push block");
        let p = GpuStereoPackPush::new(StereoMode::AnaglyphGray, (3, 2));
        assert_eq!(p.left_rows[0], [0.299, 0.587, 0.114, 0.0]);
        assert_eq!(p.right_rows[2], [0.299, 0.587, 0.114, 0.0]);
        assert_eq!((p.mode, p.eye_width, p.eye_height), (0, 3, 2));
    }

    #[test]
    fn anaglyphs_preserve_white_where_they_should() {
        // Color and half-color pass white through unchanged (each output channel's rows sum to
        // one across the eyes); Dubois's rows sum to about (1.05, 0.97, 1.07)—its least-squares
        // fit is not constrained to keep white.
        for mode in [StereoMode::AnaglyphColor, StereoMode::AnaglyphHalfColor] {
            let (l, r) = mode.anaglyph_matrices().expect("anaglyph");
            for i in 0..3 {
                let s: f32 = l[i].iter().chain(r[i].iter()).sum();
                assert!((s - 1.0).abs() < 1e-6, "{mode:?} row {i}: {s}");
            }
        }
        assert!(StereoMode::SideBySide.anaglyph_matrices().is_none());
    }
}

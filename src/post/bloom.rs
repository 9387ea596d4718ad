//! `bloom_down[l]`, `bloom_up[l]`: threshold-free, energy-conserving bloom on the linear HDR
//! radiance (`glsl/bloom_down.comp`, `glsl/bloom_up.comp`; Oetke 2017 §4.4). The radiance is
//! box-downsampled N times (m_1 … m_N); going back up, u_N = m_N and u_l = m_l + up(u_{l+1}),
//! so u_1 holds the sum of N ever wider blurs; the output is
//! (1 − s)·radiance + (s / N)·up(u_1), s the strength. Each step conserves radiance × area
//! (box means over even sides, bilinear ×2 upsampling), so the output's total equals the
//! input's: bloom only moves light. N is the number of halvings that keep both sides even
//! (at most [`MAX_LEVELS`]).

use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};

/// Push constants of `bloom_up.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBloomUpPush {
    pub base_weight: f32,
    pub coarse_weight: f32,
}

crate::push_constants!(GpuBloomUpPush {
    base_weight,
    coarse_weight
});

/// The widest blur: 2⁶ = 64 pixels.
pub const MAX_LEVELS: u32 = 6;

/// The levels of a `w`×`h` frame's chain: halvings while both sides stay even.
pub fn levels((w, h): (u32, u32)) -> u32 {
    (w | h).trailing_zeros().min(MAX_LEVELS)
}

pub struct BloomPass {
    down: ComputePipeline,
    up: ComputePipeline,
    sampler: vk::Sampler,
    strength: f32,
}

impl BloomPass {
    /// `sampler`: nearest (both shaders fetch texels).
    pub fn new(ctx: &Context, strength: f32, sampler: vk::Sampler) -> Result<Self, VkError> {
        let down = ctx.compute_pipeline("bloom_down.comp", None, &[])?;
        let up = ctx.compute_pipeline("bloom_up.comp", PushLayout::of::<GpuBloomUpPush>(), &[])?;
        Ok(Self {
            down,
            up,
            sampler,
            strength,
        })
    }

    /// Declares the chain over `radiance` (`size`); returns the bloomed radiance (the input
    /// itself when the size allows no level).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        radiance: ImageHandle,
        (w, h): (u32, u32),
    ) -> ImageHandle {
        let n = levels((w, h));
        if n == 0 {
            return radiance;
        }
        let c = Shader::Compute;
        let image = |g: &mut RenderGraph, name: String, l: u32| {
            g.create_image(ImageDesc::new_2d(
                &name,
                vk::Format::R32G32B32A32_SFLOAT,
                w >> l,
                h >> l,
            ))
        };
        // m_0 = radiance, m_1 … m_N.
        let mut mips = vec![radiance];
        for l in 1..=n {
            let dst = image(g, format!("bloom mip {l}"), l);
            let pipe = *self.down;
            let (dw, dh) = (w >> l, h >> l);
            g.add_pass(&format!("bloom_down[{l}]"))
                .pipeline(&pipe)
                .bind_sampled(0, mips[l as usize - 1], self.sampler, c)
                .bind(1, dst, Access::StorageWrite(c))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.dispatch(dw.div_ceil(8), dh.div_ceil(8), 1);
                });
            mips.push(dst);
        }
        // u_l = m_l + up(u_{l+1}) for l = N−1 … 1, then the output at level 0.
        let mut coarse = mips[n as usize];
        for l in (0..n).rev() {
            let (base_weight, coarse_weight, name) = if l == 0 {
                (
                    1.0 - self.strength,
                    self.strength / n as f32,
                    "bloom".to_owned(),
                )
            } else {
                (1.0, 1.0, format!("bloom sum {l}"))
            };
            let dst = image(g, name, l);
            let push = GpuBloomUpPush {
                base_weight,
                coarse_weight,
            };
            let pipe = *self.up;
            let (dw, dh) = (w >> l, h >> l);
            g.add_pass(&format!("bloom_up[{l}]"))
                .pipeline(&pipe)
                .bind_sampled(0, mips[l as usize], self.sampler, c)
                .bind_sampled(1, coarse, self.sampler, c)
                .bind(2, dst, Access::StorageWrite(c))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd.dispatch(dw.div_ceil(8), dh.div_ceil(8), 1);
                });
            coarse = dst;
        }
        coarse
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_while_both_sides_are_even() {
        assert_eq!(levels((512, 512)), 6);
        assert_eq!(levels((1920, 1080)), 3);
        assert_eq!(levels((64, 48)), 4);
        assert_eq!(levels((127, 128)), 0);
    }
}

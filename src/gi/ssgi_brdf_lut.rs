//! `ssgi_brdf_lut`: the split-sum BRDF table of screen-space GI's specular term (Karis 2013,
//! Oetke 2017 §2.4, §5.4), computed once on the GPU when the renderer is built: A and B of
//! ∫ f_spec (n·l) dl = F0·A + B over n·v (x) and roughness (y), 1024 Hammersley directions per
//! texel. `glsl/ssgi_upsample.comp` combines it by Eq. 2.19.

use crate::graph::{Access, RenderGraph, Shader};
use crate::vk::{vk, Context, Image, ImageDesc, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};

/// Texels per side (the thesis uses 512² RG16F; 128² RGBA32F here: the table is smooth, and
/// lavapipe computes it in well under a second).
pub const LUT_SIZE: u32 = 128;
/// Hammersley directions per texel (Oetke 2017 §5.4).
pub const LUT_SAMPLES: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuLutPush {
    samples: u32,
}
crate::push_constants!(GpuLutPush { samples });

/// The computed table (R = A, G = B), sampled-read ready.
pub struct BrdfLut {
    pub image: Image,
}

impl BrdfLut {
    /// Creates the table and fills it with one compute dispatch.
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC;
        // The graph imports it in the sampled layout, which the clear puts it in.
        let image = ctx.create_zeroed_image(
            &ImageDesc::new_2d(
                "ssgi brdf lut",
                vk::Format::R32G32B32A32_SFLOAT,
                LUT_SIZE,
                LUT_SIZE,
            )
            .with_usage(usage),
            Access::Sampled(Shader::Compute).info().layout,
        )?;
        let lut = Self { image };
        lut.compute(ctx)?;
        Ok(lut)
    }

    fn compute(&self, ctx: &Context) -> Result<(), VkError> {
        let pipe =
            ctx.compute_pipeline("ssgi_brdf_lut.comp", PushLayout::of::<GpuLutPush>(), &[])?;
        let mut g = RenderGraph::new();
        let c = Shader::Compute;
        let lut = g.import_image(&self.image, Access::Sampled(c));
        let push = GpuLutPush {
            samples: LUT_SAMPLES,
        };
        let groups = LUT_SIZE.div_ceil(8);
        g.add_pass("ssgi_brdf_lut")
            .pipeline(&pipe)
            .bind(0, lut, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups, groups, 1);
            });
        g.mark_output(lut);
        crate::graph::run_once(ctx, g)
            .map(|_| ())
            .map_err(|e| match e {
                crate::graph::OneShotError::Vk(e) => e,
                crate::graph::OneShotError::Graph(e) => VkError::Invalid(e.to_string()),
            })
    }

    /// Reads the table back: `LUT_SIZE²` texels (A, B), row by row (roughness rows).
    pub fn read(&self, ctx: &Context) -> Result<Vec<[f32; 2]>, VkError> {
        let bytes = u64::from(LUT_SIZE * LUT_SIZE) * 16;
        let buffer = crate::graph::readback_buffer(ctx, "ssgi brdf lut readback", bytes)?;
        let mut g = RenderGraph::new();
        let lut = g.import_image(&self.image, Access::Sampled(Shader::Compute));
        let buf = g.import_buffer(&buffer, Access::HostRead);
        crate::graph::add_readback(&mut g, "readback_lut", lut, buf);
        let run = crate::graph::run_once(ctx, g);
        let values = buffer.mapped().map(|m| {
            bytemuck::cast_slice::<u8, [f32; 4]>(&m[..bytes as usize])
                .iter()
                .map(|t| [t[0], t[1]])
                .collect()
        });
        match run {
            Ok(_) => values.ok_or_else(|| VkError::Invalid("readback buffer not mapped".into())),
            Err(crate::graph::OneShotError::Vk(e)) => Err(e),
            Err(crate::graph::OneShotError::Graph(e)) => Err(VkError::Invalid(e.to_string())),
        }
    }
}

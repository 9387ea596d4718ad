//! The demo graph: the smallest frame that exercises every part of the render graph.
//!
//! `demo_gradient` (compute) writes a pattern → `demo_blit` (graphics) samples it into a color
//! attachment → `demo_pack` (compute) packs it to RGBA8 → `demo_readback` (transfer) copies it
//! into a host-visible buffer. `demo_unused` writes an image nobody reads and is culled. The
//! pattern image and the packed image have disjoint lifetimes, so the graph aliases them.

use crate::graph::{Access, GraphExecutor, RenderGraph, Shader};
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, GraphicsPipeline, GraphicsPipelineDesc,
    ImageDesc, MemoryLocation, VkError,
};

/// Pipelines and the read-back buffer of the demo graph.
pub struct Demo {
    pub width: u32,
    pub height: u32,
    gradient: ComputePipeline,
    blit: GraphicsPipeline,
    pack: ComputePipeline,
    sampler: crate::vk::Sampler,
    readback: Buffer,
}

impl Demo {
    pub fn new(ctx: &Context, width: u32, height: u32) -> Result<Self, VkError> {
        let gradient = ctx.compute_pipeline("demo_gradient.comp", None, &[])?;
        let blit_desc = GraphicsPipelineDesc::fullscreen(
            "fullscreen.vert",
            "demo_blit.frag",
            vk::Format::R32G32B32A32_SFLOAT,
        );
        let blit = ctx.graphics_pipeline(&blit_desc)?;
        let pack = ctx.compute_pipeline("demo_pack.comp", None, &[])?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let readback = ctx.create_buffer(&BufferDesc {
            name: "demo readback".into(),
            size_bytes: u64::from(width) * u64::from(height) * 4,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?;
        Ok(Self {
            width,
            height,
            gradient,
            blit,
            pack,
            sampler,
            readback,
        })
    }

    /// Declares the demo frame.
    pub fn graph(&self) -> RenderGraph {
        let (w, h) = (self.width, self.height);
        let mut g = RenderGraph::new();
        let pattern = g.create_image(ImageDesc::new_2d(
            "demo pattern",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let color = g.create_image(ImageDesc::new_2d(
            "demo color",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let packed = g.create_image(ImageDesc::new_2d(
            "demo packed",
            vk::Format::R8G8B8A8_UNORM,
            w,
            h,
        ));
        let unused = g.create_image(ImageDesc::new_2d(
            "demo unused",
            vk::Format::R8G8B8A8_UNORM,
            w,
            h,
        ));
        let readback = g.import_buffer(&self.readback, Access::HostRead);
        let groups = (w.div_ceil(8), h.div_ceil(8));

        let c = Shader::Compute;
        let pipe = *self.gradient;
        g.add_pass("demo_gradient")
            .pipeline(&pipe)
            .bind(0, pattern, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });

        let (pipe, sampler) = (*self.blit, self.sampler.raw);
        g.add_pass("demo_blit")
            .pipeline(&pipe)
            .bind_sampled(0, pattern, sampler, Shader::Fragment)
            // The full-screen triangle covers every pixel; the clear only avoids loading
            // undefined contents.
            .color(color, crate::graph::Load::Clear([0.0; 4]))
            .record(move |ctx| {
                ctx.begin_rendering();
                ctx.bind(&pipe);
                ctx.cmd.draw(3, 1);
                ctx.cmd.end_rendering();
            });

        let pipe = *self.pack;
        g.add_pass("demo_pack")
            .pipeline(&pipe)
            .bind_sampled(0, color, sampler, c)
            .bind(1, packed, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });

        g.add_pass("demo_unused")
            .write(unused, Access::TransferWrite)
            .record(move |ctx| {
                let img = ctx.image(unused);
                ctx.cmd
                    .clear_color_image(img.raw, vk::ClearColorValue { float32: [1.0; 4] }, 1, 1);
            });

        crate::graph::add_readback(&mut g, "demo_readback", packed, readback);
        g
    }

    /// Builds the executor of the demo graph.
    pub fn executor(
        &self,
        ctx: &Context,
        frames_in_flight: usize,
    ) -> Result<GraphExecutor, crate::graph::GraphError> {
        GraphExecutor::new(ctx, self.graph(), frames_in_flight)
    }

    /// RGBA8 pixels of the last completed frame (call after the frame's fence).
    pub fn pixels(&self) -> Vec<u8> {
        self.readback
            .mapped()
            .map(<[u8]>::to_vec)
            .unwrap_or_default()
    }
}

/// The RGBA8 value the demo frame must produce at (x, y): the pattern of
/// `glsl/include/demo_pattern.glsl`, channels rotated by `demo_blit`, quantized by `demo_pack`.
pub fn expected_pixel(x: u32, y: u32, width: u32, height: u32) -> [u8; 4] {
    let r = (x as f32 + 0.5) / width as f32;
    let g = (y as f32 + 0.5) / height as f32;
    let b = ((x ^ y) & 255) as f32 / 255.0;
    let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(b), q(r), q(g), 255]
}

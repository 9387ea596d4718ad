//! `oit_gather`: draws the surfaces with MTL d < 1 over the finished opaque depth (tested, not
//! written), shades each fragment with the deferred pass's direct light and its emission, and
//! appends it to its pixel's linked list (`glsl/gbuffer.vert`, `glsl/oit_gather.frag`).

use super::gbuffer::GpuGbufferPush;
use super::scene_gpu::{vertex_attributes, SceneInputs};
use super::DEPTH;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, VkError};

/// The linked lists of a frame: head pointers (r32ui), nodes and counters.
#[derive(Clone, Copy, Debug)]
pub struct OitLists {
    pub heads: ImageHandle,
    pub nodes: BufferHandle,
    pub counters: BufferHandle,
}

pub struct OitGatherPass {
    pipeline: GraphicsPipeline,
}

impl OitGatherPass {
    /// `phong`, `ggx`, `textures`, `alpha_maps`: what the scene's materials have (the shader
    /// compiles in only those).
    pub fn new(
        ctx: &Context,
        (phong, ggx, textures, alpha_maps): (bool, bool, bool, bool),
    ) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            // The G-buffer's vertex stage: the same positions, so the depth test against the
            // opaque depth compares equal transforms.
            vertex: "gbuffer.vert".into(),
            geometry: None,
            fragment: "oit_gather.frag".into(),
            push: crate::vk::PushLayout::of::<GpuGbufferPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: vertex_attributes(),
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: false,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: crate::spec_constants![
                HAS_PHONG = phong,
                HAS_GGX = ggx,
                HAS_TEXTURES = textures,
                HAS_ALPHA_MAP = alpha_maps,
            ]
            .to_vec(),
        })?;
        Ok(Self { pipeline })
    }

    /// Declares the pass appending the transparent draws' fragments to `lists` (cleared by
    /// `oit_clear`), tested against the opaque `depth`.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        lists: OitLists,
        depth: ImageHandle,
        shadow_maps: ImageHandle,
        shadow_sampler: vk::Sampler,
    ) {
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let textures = scene.textures.clone();
        let placeholder = scene.placeholder();
        let f = Shader::Fragment;
        g.add_pass("oit_gather")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(f))
            .bind_one_of_sampled(2, textures.clone(), scene.texture_sampler, f)
            .bind(3, scene.materials_pbr, Access::StorageRead(f))
            .bind_sampled(4, shadow_maps, shadow_sampler, f)
            .bind(5, lists.heads, Access::StorageReadWrite(f))
            .bind(6, lists.nodes, Access::StorageWrite(f))
            .bind(7, lists.counters, Access::StorageReadWrite(f))
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .depth_read(depth)
            .record(move |ctx| {
                ctx.begin_rendering();
                let texture = |t: Option<usize>| {
                    t.and_then(|i| textures.get(i).copied())
                        .unwrap_or(placeholder)
                };
                ctx.bind_with(&pipe, &[(2, placeholder)]);
                ctx.bind_vertex_buffer(vertices);
                ctx.bind_index_buffer(indices);
                if let Ok(lists) = draws.read() {
                    let mut bound = None;
                    for d in &lists.transparent {
                        if d.texture != bound {
                            ctx.push_with(&pipe, &[(2, texture(d.texture))]);
                            bound = d.texture;
                        }
                        let push = GpuGbufferPush::of(d);
                        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                        ctx.cmd
                            .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    }
                }
                ctx.cmd.end_rendering();
            });
    }
}

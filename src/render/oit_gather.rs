//! `oit_gather`: draws the surfaces with MTL d < 1 over the finished opaque depth (tested, not
//! written), shades each fragment with the deferred pass's direct light and its emission, and
//! appends it to its pixel's linked list (`glsl/gbuffer.vert`, `glsl/oit_gather.frag`). Under a
//! GI method that gives transparent layers indirect light (the path tracer), the fragments
//! also trace its voxel paths (`glsl/oit_gather_indirect.frag`).

use super::gbuffer::GpuGbufferPush;
use super::scene_gpu::{vertex_attributes, SceneInputs};
use super::DEPTH;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, VkError};
use crate::voxel::attributes::AttributeHandles;

/// The linked lists of a frame: head pointers (r32ui), nodes and counters.
#[derive(Clone, Copy, Debug)]
pub struct OitLists {
    pub heads: ImageHandle,
    pub nodes: BufferHandle,
    pub counters: BufferHandle,
}

/// What the fragments' voxel paths read: the GI method's ray parameters (a `GpuGiPush` in a
/// buffer), the voxel hierarchy, the ray-mask table and the attribute volumes.
#[derive(Clone, Copy, Debug)]
pub struct OitIndirect {
    pub params: BufferHandle,
    pub voxels: ImageHandle,
    pub lut: BufferHandle,
    pub attributes: AttributeHandles,
}

pub struct OitGatherPass {
    pipeline: GraphicsPipeline,
    /// The variant that adds the voxel paths' indirect light, made when the GI method gives
    /// transparent layers any; a frame without its inputs draws with `pipeline`.
    indirect: Option<GraphicsPipeline>,
}

impl OitGatherPass {
    /// `phong`, `ggx`, `textures`, `alpha_maps`: what the scene's materials have (the shader
    /// compiles in only those). `indirect`: make the indirect-light variant, with emission
    /// reads when `Some(true)` (a scene with emitters).
    pub fn new(
        ctx: &Context,
        materials: (bool, bool, bool, bool),
        indirect: Option<bool>,
    ) -> Result<Self, VkError> {
        Ok(Self {
            pipeline: Self::pipeline(ctx, materials, None)?,
            indirect: indirect
                .map(|emission| Self::pipeline(ctx, materials, Some(emission)))
                .transpose()?,
        })
    }

    fn pipeline(
        ctx: &Context,
        (phong, ggx, textures, alpha_maps): (bool, bool, bool, bool),
        indirect: Option<bool>,
    ) -> Result<GraphicsPipeline, VkError> {
        let mut spec = crate::spec_constants![
            HAS_PHONG = phong,
            HAS_GGX = ggx,
            HAS_TEXTURES = textures,
            HAS_ALPHA_MAP = alpha_maps,
        ]
        .to_vec();
        if let Some(emission) = indirect {
            spec.extend(crate::spec_constants![HAS_EMISSION = emission]);
        }
        ctx.graphics_pipeline(&GraphicsPipelineDesc {
            // The G-buffer's vertex stage: the same positions, so the depth test against the
            // opaque depth compares equal transforms.
            vertex: "gbuffer.vert".into(),
            geometry: None,
            fragment: match indirect {
                Some(_) => "oit_gather_indirect.frag".into(),
                None => "oit_gather.frag".into(),
            },
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
            spec,
        })
    }

    /// Declares the pass appending the transparent draws' fragments to `lists` (cleared by
    /// `oit_clear`), tested against the opaque `depth`; with `indirect`, the fragments add the
    /// voxel paths' indirect light (when this pass made that variant).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        lists: OitLists,
        (depth, shadow_maps): (ImageHandle, ImageHandle),
        sampler: vk::Sampler,
        indirect: Option<OitIndirect>,
    ) {
        let (pipe, indirect) = match (&self.indirect, indirect) {
            (Some(p), Some(i)) => (**p, Some(i)),
            _ => (*self.pipeline, None),
        };
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let textures = scene.textures.clone();
        let placeholder = scene.placeholder();
        let f = Shader::Fragment;
        let mut pass = g
            .add_pass("oit_gather")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(f))
            .bind_one_of_sampled(2, textures.clone(), scene.texture_sampler, f)
            .bind(3, scene.materials_pbr, Access::StorageRead(f))
            .bind_sampled(4, shadow_maps, sampler, f)
            .bind(5, lists.heads, Access::StorageReadWrite(f))
            .bind(6, lists.nodes, Access::StorageWrite(f))
            .bind(7, lists.counters, Access::StorageReadWrite(f))
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .depth_read(depth);
        if let Some(i) = indirect {
            let v = i.attributes;
            // Without emitters the shader never reads its emission binding; albedo fills it.
            pass = pass
                .bind(8, i.params, Access::StorageRead(f))
                .bind_sampled(9, i.voxels, sampler, f)
                .bind(10, i.lut, Access::StorageRead(f))
                .bind_sampled(11, v.albedo, sampler, f)
                .bind_sampled(12, v.normal, sampler, f)
                .bind_sampled(13, v.emission.unwrap_or(v.albedo), sampler, f);
        }
        pass.record(move |ctx| {
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

#[cfg(test)]
mod tests {
    /// The indirect variant's parameter buffer holds what the ray passes get as push
    /// constants: the shader's `GpuGiPush` has the Rust struct's names, offsets and sizes.
    #[test]
    fn gi_params_buffer_matches_the_ray_passes_push_constants() {
        let files = ["oit_gather_indirect.frag"];
        crate::vk::check_struct_against::<crate::gi::GpuGiPush>(&files, "GpuGiPush")
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

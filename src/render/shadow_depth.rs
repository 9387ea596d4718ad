//! `shadow_depth`: one depth layer per shadow view (spot perspective, cube face, paraboloid
//! hemisphere, directional ortho, directional cascade), rendered in one layered pass whose
//! geometry shader routes each draw to its view's layer (`glsl/shadow_depth.{vert,geom,frag}`,
//! `glsl/shadow_depth_paraboloid.frag`).

use super::scene_gpu::{record_shadow_and_cascade_views, GpuShadowViewPush, SceneInputs};
use super::DEPTH;
use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};

pub struct ShadowDepthPass {
    pipeline: GraphicsPipeline,
}

impl ShadowDepthPass {
    /// `paraboloid`: some view is a paraboloid hemisphere, whose depth the fragment shader
    /// writes (which costs the other maps their early depth test, so only scenes that have
    /// them pay for it); `has_dissolve`: some material has MTL d < 1 (hashed coverage).
    pub fn new(ctx: &Context, paraboloid: bool, has_dissolve: bool) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: "shadow_depth.vert".into(),
            geometry: Some("shadow_depth.geom".into()),
            fragment: if paraboloid {
                "shadow_depth_paraboloid.frag".into()
            } else {
                "shadow_depth.frag".into()
            },
            push: crate::vk::PushLayout::of::<GpuShadowViewPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: vec![(vk::Format::R32G32B32_SFLOAT, 0)],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: crate::spec_constants![HAS_DISSOLVE = has_dissolve].to_vec(),
        })?;
        Ok(Self { pipeline })
    }

    /// Declares the shadow maps of `views` views at `resolution`² (the lights' own views, then
    /// the directional lights' cascades; a 1x1 cleared layer when there are none, so the
    /// shading pass always has a map to bind) and returns them.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        views: u32,
        resolution: u32,
    ) -> ImageHandle {
        let res = if views == 0 { 1 } else { resolution };
        let maps = g.create_image(
            ImageDesc::new_2d("shadow maps", DEPTH, res, res).with_layers(views.max(1)),
        );
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        g.add_pass("shadow_depth")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Geometry))
            .bind(1, scene.materials, Access::StorageRead(Shader::Fragment))
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .depth(maps, Load::ClearDepth(1.0))
            .record(move |ctx| {
                record_shadow_and_cascade_views(ctx, &pipe, (vertices, indices), &draws)
            });
        maps
    }
}

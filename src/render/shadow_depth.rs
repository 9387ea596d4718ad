//! `shadow_depth`: one depth layer per shadow view (spot perspective, cube face, paraboloid
//! hemisphere, directional ortho, directional cascade), rendered in one layered pass whose
//! geometry shader routes each draw to its view's layer (`glsl/shadow_depth.{vert,geom,frag}`,
//! `glsl/shadow_depth_paraboloid.frag`).

use super::scene_gpu::{record_shadow_and_cascade_views, Draw, GpuShadowViewPush, SceneInputs};
use super::DEPTH;
use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};

pub struct ShadowDepthPass {
    pipeline: GraphicsPipeline,
    /// Some material has an alpha map, which the fragments sample (binding 2).
    has_alpha_maps: bool,
}

impl ShadowDepthPass {
    /// `paraboloid`: some view is a paraboloid hemisphere, whose depth the fragment shader
    /// writes (which costs the other maps their early depth test, so only scenes that have
    /// them pay for it); `has_dissolve`: some material has MTL d < 1 (hashed coverage);
    /// `has_alpha_maps`: some material has per-texel alpha (`scene::AlphaMap`), tested per
    /// fragment.
    pub fn new(
        ctx: &Context,
        paraboloid: bool,
        has_dissolve: bool,
        has_alpha_maps: bool,
    ) -> Result<Self, VkError> {
        use std::mem::offset_of;
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
            // Position, and the texture coordinates of the alpha maps.
            vertex_attributes: vec![
                (
                    vk::Format::R32G32B32_SFLOAT,
                    offset_of!(super::gpu::GpuVertex, position) as u32,
                ),
                (
                    vk::Format::R32G32_SFLOAT,
                    offset_of!(super::gpu::GpuVertex, uv) as u32,
                ),
            ],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: vec![(0, u32::from(has_dissolve)), (1, u32::from(has_alpha_maps))],
        })?;
        Ok(Self {
            pipeline,
            has_alpha_maps,
        })
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
        let (sampler, placeholder) = (scene.texture_sampler, scene.placeholder());
        let pass = g
            .add_pass("shadow_depth")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Geometry))
            .bind(1, scene.materials, Access::StorageRead(Shader::Fragment));
        // Without alpha maps the shader never samples: the placeholder fills the binding.
        let textures = self.has_alpha_maps.then(|| scene.textures.clone());
        let pass = match &textures {
            Some(t) => pass.bind_one_of_sampled(2, t.clone(), sampler, Shader::Fragment),
            None => pass.bind_sampled(2, placeholder, sampler, Shader::Fragment),
        };
        pass.read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .depth(maps, Load::ClearDepth(1.0))
            .record(move |ctx| {
                // The draw's texture (its alpha map), pushed when it differs from the last
                // draw's.
                let mut bound = None;
                let mut per_draw = |d: &Draw| {
                    let Some(t) = &textures else { return };
                    if bound != Some(d.texture) {
                        let pick = d.texture.and_then(|i| t.get(i).copied());
                        ctx.push_with(&pipe, &[(2, pick.unwrap_or(placeholder))]);
                        bound = Some(d.texture);
                    }
                };
                record_shadow_and_cascade_views(
                    ctx,
                    &pipe,
                    (vertices, indices),
                    &draws,
                    &mut per_draw,
                )
            });
        maps
    }
}

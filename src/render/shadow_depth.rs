//! `shadow_depth`: one depth layer per shadow view (spot perspective, cube face, paraboloid
//! hemisphere, directional ortho, directional cascade), rendered in one layered pass whose
//! geometry shader routes each draw to its view's layer (`glsl/shadow_depth.{vert,geom,frag}`,
//! `glsl/shadow_depth_paraboloid.frag`).

use super::gpu::{GpuFrame, MAX_SHADOW_VIEWS};
use super::scene_gpu::{
    hash_view_draws, record_one_view, record_shadow_and_cascade_views, Draw, DrawLists,
    GpuShadowViewPush, SceneInputs,
};
use super::DEPTH;
use crate::graph::{Access, Cache, ImageHandle, KeyHasher, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};
use std::sync::Arc;

pub struct ShadowDepthPass {
    pipeline: GraphicsPipeline,
    /// Some material has an alpha map, which the fragments sample (binding 2).
    has_alpha_maps: bool,
    /// While `shadow.cache` is on, one validity per layer of the shadow array, each layer
    /// drawn by its own pass (empty: one pass draws every layer every frame, into a
    /// transient).
    caches: Vec<Arc<Cache>>,
}

impl ShadowDepthPass {
    /// `paraboloid`: some view is a paraboloid hemisphere, whose depth the fragment shader
    /// writes (which costs the other maps their early depth test, so only scenes that have
    /// them pay for it); `has_dissolve`: some material has MTL d < 1 (hashed coverage);
    /// `has_alpha_maps`: some material has per-texel alpha (`scene::AlphaMap`), tested per
    /// fragment; `cached`: keep the maps while their views and draws stay (`shadow.cache`).
    pub fn new(
        ctx: &Context,
        paraboloid: bool,
        has_dissolve: bool,
        has_alpha_maps: bool,
        cached: bool,
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
            spec: crate::spec_constants![
                HAS_DISSOLVE = has_dissolve,
                HAS_ALPHA_MAP = has_alpha_maps
            ]
            .to_vec(),
        })?;
        let caches = if cached {
            (0..MAX_SHADOW_VIEWS)
                .map(|v| Cache::new(&format!("shadow map {v}")))
                .collect()
        } else {
            Vec::new()
        };
        Ok(Self {
            pipeline,
            has_alpha_maps,
            caches,
        })
    }

    /// Before recording frame slot `slot`, per layer of the `layers` the graph declared: a
    /// layer is rendered again only when what it is drawn from changed: its view (a light's
    /// own, moved or edited, or a cascade, whose window moves with the camera in whole
    /// texels, so only the cascades that moved render) and the draws culled into it (an
    /// object moved, deformed, switched its OBJ frame, or entered or left the view). A layer
    /// no view uses (a dropped cascade) is cleared once. The vertex, index and material
    /// buffers are fixed for the renderer's life.
    pub fn validate(&self, slot: usize, frame: &GpuFrame, draws: &DrawLists, layers: u32) {
        let views = (frame.counts[1] as usize).min(frame.shadow_views.len());
        let mut lists = draws.shadow.iter().chain(&draws.cascades);
        for (v, cache) in self.caches.iter().take(layers.max(1) as usize).enumerate() {
            let mut key = KeyHasher::default();
            match lists.next().filter(|_| v < views) {
                Some(list) => {
                    key.u64(v as u64)
                        .bytes(bytemuck::bytes_of(&frame.shadow_views[v]));
                    hash_view_draws(&mut key, std::iter::once(list));
                }
                None => {
                    key.u64(u64::MAX);
                }
            }
            cache.validate(slot, key.finish());
        }
    }

    /// The validities of the first `layers` layers (none while `shadow.cache` is off).
    pub fn caches(&self, layers: u32) -> &[Arc<Cache>] {
        &self.caches[..self.caches.len().min(layers.max(1) as usize)]
    }

    /// Declares the shadow maps of `views` views at `resolution`² (the lights' own views, then
    /// the directional lights' cascades; a 1x1 cleared layer when there are none, so the
    /// shading pass always has a map to bind) and returns them. Cached, each layer is drawn
    /// by its own pass, `shadow_depth[v]`, recorded only in frames where its view or draws
    /// changed (see [`Self::validate`]); otherwise one pass draws every layer.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        views: u32,
        resolution: u32,
    ) -> ImageHandle {
        let res = if views == 0 { 1 } else { resolution };
        let layers = views.max(1);
        let desc = ImageDesc::new_2d("shadow maps", DEPTH, res, res).with_layers(layers);
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let placeholder = scene.placeholder();
        // Without alpha maps the shader never samples: the placeholder fills binding 2.
        let textures = self.has_alpha_maps.then(|| scene.textures.clone());
        fn declare_pass<'g>(
            g: &'g mut RenderGraph,
            name: &str,
            pipe: &crate::vk::PipelineHandle,
            scene: &SceneInputs,
            textures: &Option<Vec<ImageHandle>>,
        ) -> crate::graph::PassBuilder<'g> {
            let (sampler, placeholder) = (scene.texture_sampler, scene.placeholder());
            let pass = g
                .add_pass(name)
                .pipeline(pipe)
                .bind(0, scene.frame, Access::StorageRead(Shader::Geometry))
                .bind(1, scene.materials, Access::StorageRead(Shader::Fragment));
            match textures {
                Some(t) => pass.bind_one_of_sampled(2, t.clone(), sampler, Shader::Fragment),
                None => pass.bind_sampled(2, placeholder, sampler, Shader::Fragment),
            }
            .read(scene.vertices, Access::VertexBuffer)
            .read(scene.indices, Access::IndexBuffer)
        }
        if !self.caches.is_empty() {
            let caches = self.caches(layers);
            let maps = g.create_cached_image(desc, Access::Sampled(Shader::Fragment), caches);
            for (v, cache) in caches.iter().enumerate() {
                let v = v as u32;
                let layer = g.layer(maps, v);
                let draws = scene.draws.clone();
                let textures = textures.clone();
                declare_pass(g, &format!("shadow_depth[{v}]"), &pipe, scene, &textures)
                    .cached(Some(cache))
                    .depth(layer, Load::ClearDepth(1.0))
                    .record(move |ctx| {
                        let mut per_draw = alpha_map_binder(ctx, &pipe, &textures, placeholder);
                        record_one_view(ctx, &pipe, (vertices, indices), &draws, v, &mut per_draw)
                    });
            }
            return maps;
        }
        let maps = g.create_image(desc);
        let draws = scene.draws.clone();
        declare_pass(g, "shadow_depth", &pipe, scene, &textures)
            .depth(maps, Load::ClearDepth(1.0))
            .record(move |ctx| {
                let mut per_draw = alpha_map_binder(ctx, &pipe, &textures, placeholder);
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

/// Before each draw: pushes the draw's texture (its alpha map) to binding 2 when it differs
/// from the last draw's; nothing without alpha maps.
fn alpha_map_binder<'a>(
    ctx: &'a crate::graph::PassContext,
    pipe: &'a crate::vk::PipelineHandle,
    textures: &'a Option<Vec<ImageHandle>>,
    placeholder: ImageHandle,
) -> impl FnMut(&Draw) + 'a {
    let mut bound = None;
    move |d: &Draw| {
        let Some(t) = textures else { return };
        if bound != Some(d.texture) {
            let pick = d.texture.and_then(|i| t.get(i).copied());
            ctx.push_with(pipe, &[(2, pick.unwrap_or(placeholder))]);
            bound = Some(d.texture);
        }
    }
}

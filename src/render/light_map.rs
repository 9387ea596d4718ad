//! `light_map`: reflective shadow maps (Dachsbacher and Stamminger 2005) over the shadow
//! views — reflected radiance, world position and normal of the surfaces each light sees —
//! which the GI methods read as the radiance at a ray's hit (`glsl/light_map.{vert,geom,frag}`).
//!
//! In scenes with albedo textures (`map_Kd`) or GGX metalness maps (`map_Pm`) a texel samples
//! the draw's maps as the G-buffer does: the pass binds the scene's textures one of them per
//! draw (`.bind_one_of_sampled`, as `gbuffer` does) rather than reading the voxel volumes'
//! half-float map buffer (`voxel::maps`): the textures are on the device already in every
//! scene that has maps, whereas that buffer exists only where a voxel volume samples them, and
//! the sampler's mip selection from the texel's own footprint comes with them. Other scenes
//! bind the placeholder and never sample (a specialization constant).

use super::gpu::GpuFrame;
use super::scene_gpu::{
    hash_view_draws, record_shadow_views, Draw, DrawLists, GpuShadowViewPush, SceneInputs,
};
use super::DEPTH;
use crate::graph::{Access, Cache, ImageHandle, KeyHasher, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};
use std::sync::Arc;

/// Reflected radiance in the light maps. f32, not f16: light intensities from 1e-6 to 1e6 W/sr
/// (the extremes `tests/extremes.rs` renders) put it outside f16's range (max 65504, normal
/// down to 6e-5); f16 lost 1.5% of the peak at 1e-6 and overflowed to Inf at 1e6.
const LIGHT_MAP_RADIANCE: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const LIGHT_MAP_POSITION: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const LIGHT_MAP_NORMAL: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The light-map layers of a frame, one per shadow view.
#[derive(Clone, Copy, Debug)]
pub struct LightMaps {
    pub radiance: ImageHandle,
    pub position: ImageHandle,
    pub normal: ImageHandle,
}

pub struct LightMapPass {
    pipeline: GraphicsPipeline,
    /// The texels sample the draws' albedo textures and metalness maps.
    has_maps: bool,
    /// The maps' validity while `shadow.cache` is on (`None`: rendered every frame, into
    /// transients).
    cache: Option<Arc<Cache>>,
}

impl LightMapPass {
    /// `has_dissolve`: some material has MTL d < 1, whose coverage the light map shares with
    /// the shadow maps. `has_ggx`: some material is GGX, whose texels store only the diffuse
    /// part (`glsl/light_map.frag`). `area_lights`: the area lights' (paraboloid) views get
    /// light maps too — only the hemisphere method reads them (`glsl/light_map.geom`).
    /// `has_maps`: some material has an albedo texture, or a GGX one a metalness map
    /// ([`Self::scene_has_maps`]), which the texels sample. `has_alpha_maps`: some material
    /// has per-texel alpha (`scene::AlphaMap`, implies `has_maps`), tested per texel.
    /// `cached`: keep the maps while their lights, views and draws stay (`shadow.cache`).
    pub fn new(
        ctx: &Context,
        has_dissolve: bool,
        has_ggx: bool,
        area_lights: bool,
        (has_maps, has_alpha_maps, cached): (bool, bool, bool),
    ) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: "light_map.vert".into(),
            geometry: Some("light_map.geom".into()),
            fragment: "light_map.frag".into(),
            push: crate::vk::PushLayout::of::<GpuShadowViewPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: super::scene_gpu::vertex_attributes(),
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![LIGHT_MAP_RADIANCE, LIGHT_MAP_POSITION, LIGHT_MAP_NORMAL],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: crate::spec_constants![
                HAS_DISSOLVE = has_dissolve,
                HAS_GGX = has_ggx,
                AREA_LIGHT_MAPS = area_lights,
                HAS_MAPS = has_maps || has_alpha_maps,
                HAS_ALPHA_MAP = has_alpha_maps,
            ]
            .to_vec(),
        })?;
        Ok(Self {
            pipeline,
            has_maps: has_maps || has_alpha_maps,
            cache: cached.then(|| Cache::new("light maps")),
        })
    }

    /// Before recording frame slot `slot`: the maps are rendered again only when what they
    /// are drawn from changed: the lights (a texel's reflected radiance is lit by every light
    /// of the frame), the lights' own views, and the draws culled into each (the cascades
    /// have no light maps). Materials and textures are fixed for the renderer's life.
    pub fn validate(&self, slot: usize, frame: &GpuFrame, draws: &DrawLists) {
        let Some(cache) = &self.cache else { return };
        let lights = (frame.counts[0] as usize).min(frame.lights.len());
        let views = draws.shadow.len().min(frame.shadow_views.len());
        let mut key = KeyHasher::default();
        key.u64(lights as u64)
            .bytes(bytemuck::cast_slice(&frame.lights[..lights]))
            .u64(views as u64)
            .bytes(bytemuck::cast_slice(&frame.shadow_views[..views]));
        hash_view_draws(&mut key, draws.shadow.iter());
        cache.validate(slot, key.finish());
    }

    /// The maps' validity (`None`: `shadow.cache` is off).
    pub fn cache(&self) -> Option<&Arc<Cache>> {
        self.cache.as_ref()
    }

    /// Whether the texels of `scene` sample maps: a drawn material has an albedo texture, or
    /// is GGX with a metalness map (roughness and emission do not enter a light-map texel).
    pub fn scene_has_maps(scene: &crate::scene::Scene) -> bool {
        scene.has_albedo_textures()
            || scene
                .materials
                .iter()
                .any(|m| m.ggx.is_some() && m.pbr_maps.metallic.is_some())
    }

    /// Declares `views` layers of `resolution`² light maps.
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        views: u32,
        resolution: u32,
    ) -> LightMaps {
        let res = resolution.max(1);
        let layers = views.max(1);
        let desc =
            |name: &str, format| ImageDesc::new_2d(name, format, res, res).with_layers(layers);
        // The GI passes sample the maps; the depth buffer lives only inside the pass.
        let mut kept = |name: &str, format| match &self.cache {
            Some(c) => g.create_cached_image(
                desc(name, format),
                Access::Sampled(Shader::Compute),
                std::slice::from_ref(c),
            ),
            None => g.create_image(desc(name, format)),
        };
        let maps = LightMaps {
            radiance: kept("light map radiance", LIGHT_MAP_RADIANCE),
            position: kept("light map position", LIGHT_MAP_POSITION),
            normal: kept("light map normal", LIGHT_MAP_NORMAL),
        };
        let depth = g.create_image(desc("light map depth", DEPTH));
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let clear = Load::Clear([0.0; 4]);
        let (sampler, placeholder) = (scene.texture_sampler, scene.placeholder());
        let pass = g
            .add_pass("light_map")
            .cached(self.cache.as_ref())
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(Shader::Fragment))
            .bind(
                2,
                scene.materials_pbr,
                Access::StorageRead(Shader::Fragment),
            );
        // Without maps the shader never samples: the placeholder fills both bindings.
        let f = Shader::Fragment;
        let textures = self.has_maps.then(|| scene.textures.clone());
        let pass = match &textures {
            Some(t) => pass
                .bind_one_of_sampled(3, t.clone(), sampler, f)
                .bind_one_of_sampled(4, t.clone(), sampler, f),
            None => pass.bind_sampled(3, placeholder, sampler, f).bind_sampled(
                4,
                placeholder,
                sampler,
                f,
            ),
        };
        pass.read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .color(maps.radiance, clear)
            .color(maps.position, clear)
            .color(maps.normal, clear)
            .depth(depth, Load::ClearDepth(1.0))
            .record(move |ctx| {
                // The draw's albedo texture and metalness map (the placeholder where it has
                // none), pushed when they differ from the last draw's.
                let mut bound = None;
                let mut per_draw = |d: &Draw| {
                    let Some(t) = &textures else { return };
                    let choice = (d.texture, d.pbr_maps[1]);
                    if bound != Some(choice) {
                        let pick = |i: Option<usize>| i.and_then(|i| t.get(i).copied());
                        let (albedo, metal) = (pick(choice.0), pick(choice.1));
                        ctx.push_with(
                            &pipe,
                            &[
                                (3, albedo.unwrap_or(placeholder)),
                                (4, metal.unwrap_or(placeholder)),
                            ],
                        );
                        bound = Some(choice);
                    }
                };
                record_shadow_views(ctx, &pipe, (vertices, indices), &draws, &mut per_draw)
            });
        maps
    }
}

//! `light_map`: reflective shadow maps (Dachsbacher and Stamminger 2005) over the shadow
//! views — reflected radiance, world position and normal of the surfaces each light sees —
//! which the GI methods read as the radiance at a ray's hit (`glsl/light_map.{vert,geom,frag}`).

use super::scene_gpu::{record_shadow_views, GpuShadowViewPush, SceneInputs};
use super::DEPTH;
use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};

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
}

impl LightMapPass {
    /// `has_dissolve`: some material has MTL d < 1, whose coverage the light map shares with
    /// the shadow maps. `has_ggx`: some material is GGX, whose texels store only the diffuse
    /// part (`glsl/light_map.frag`). `area_lights`: the area lights' (paraboloid) views get
    /// light maps too — only the hemisphere method reads them (`glsl/light_map.geom`).
    pub fn new(
        ctx: &Context,
        has_dissolve: bool,
        has_ggx: bool,
        area_lights: bool,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: "light_map.vert".into(),
            geometry: Some("light_map.geom".into()),
            fragment: "light_map.frag".into(),
            push: crate::vk::PushLayout::of::<GpuShadowViewPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: vec![
                (vk::Format::R32G32B32_SFLOAT, 0),
                (vk::Format::R32G32B32_SFLOAT, 12),
            ],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![LIGHT_MAP_RADIANCE, LIGHT_MAP_POSITION, LIGHT_MAP_NORMAL],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: vec![
                (0, u32::from(has_dissolve)),
                (1, u32::from(has_ggx)),
                (2, u32::from(area_lights)),
            ],
        })?;
        Ok(Self { pipeline })
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
        let mut layer = |name: &str, format| {
            g.create_image(ImageDesc::new_2d(name, format, res, res).with_layers(layers))
        };
        let maps = LightMaps {
            radiance: layer("light map radiance", LIGHT_MAP_RADIANCE),
            position: layer("light map position", LIGHT_MAP_POSITION),
            normal: layer("light map normal", LIGHT_MAP_NORMAL),
        };
        let depth = layer("light map depth", DEPTH);
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let clear = Load::Clear([0.0; 4]);
        g.add_pass("light_map")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(Shader::Fragment))
            .bind(
                2,
                scene.materials_pbr,
                Access::StorageRead(Shader::Fragment),
            )
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .color(maps.radiance, clear)
            .color(maps.position, clear)
            .color(maps.normal, clear)
            .depth(depth, Load::ClearDepth(1.0))
            .record(move |ctx| record_shadow_views(ctx, &pipe, (vertices, indices), &draws));
        maps
    }
}

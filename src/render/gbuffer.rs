//! `gbuffer`: albedo, normal, (Phong or GGX scenes) specular lobe, (scenes with emitters)
//! emission, and depth of the camera view (`glsl/gbuffer.{vert,frag}`). Textures, bump maps and
//! the MTL PBR maps (roughness, metallic, emission) are chosen per draw among the declared ones
//! (`.bind_one_of_sampled`).

use super::scene_gpu::{vertex_attributes, SceneInputs};
use super::{DEPTH, GBUFFER_COLOR};
use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, VkError};

/// Push constants of `gbuffer.vert` (128 bytes, the least every device offers).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuGbufferPush {
    pub model: [f32; 16],
    pub material: u32,
    pub _pad: [u32; 3],
    /// The first three rows of prev_model · model⁻¹: the draw's motion in world space since
    /// the previous frame (identity for a draw that did not move), for the motion vectors.
    pub motion: [f32; 12],
}

crate::push_constants!(GpuGbufferPush {
    model,
    material,
    _pad,
    motion
});

impl GpuGbufferPush {
    /// The push constants of one draw (its model matrix, material and motion), shared by
    /// every pass that draws through `gbuffer.vert` (the G-buffer and the transparency lists).
    pub fn of(d: &super::scene_gpu::Draw) -> Self {
        // Exactly the identity for a draw that did not move (not model · model⁻¹ rounded).
        let motion = if d.prev_model == d.model {
            glam::Mat4::IDENTITY
        } else {
            d.prev_model * d.model.inverse()
        };
        let rows = [motion.row(0), motion.row(1), motion.row(2)];
        let mut m = [0.0f32; 12];
        for (i, r) in rows.iter().enumerate() {
            m[4 * i..4 * i + 4].copy_from_slice(&r.to_array());
        }
        Self {
            model: d.model.to_cols_array(),
            material: d.material,
            _pad: [0; 3],
            motion: m,
        }
    }
}

/// The G-buffer images of a frame.
#[derive(Clone, Copy, Debug)]
pub struct Gbuffer {
    pub albedo: ImageHandle,
    pub normal: ImageHandle,
    /// The specular lobe, only in scenes with Phong or GGX materials: rgb Phong ρs or GGX F0,
    /// a the lobe kind (1 Phong, 2 GGX); `normal`'s w is the exponent or the roughness.
    pub specular: Option<ImageHandle>,
    /// Emitted radiance (rgb, W/(m²·sr)), only in scenes with emissive materials.
    pub emission: Option<ImageHandle>,
    /// Motion vectors, only in scenes with moving objects under TAA: per pixel the surface
    /// point's un-jittered NDC in the previous frame minus its un-jittered NDC now (rg).
    pub motion: Option<ImageHandle>,
    pub depth: ImageHandle,
}

/// The motion vectors' format: NDC offsets, 2⁻¹¹ relative (a 0.1 NDC motion to 5e-5 NDC).
pub const MOTION_FORMAT: vk::Format = vk::Format::R16G16_SFLOAT;

pub struct GbufferPass {
    pipeline: GraphicsPipeline,
    /// The scene has Phong or GGX materials.
    has_lobe: bool,
    has_emission: bool,
    has_motion: bool,
}

/// The material models a scene's G-buffer carries (each gates an attachment or shader code).
#[derive(Clone, Copy, Debug, Default)]
pub struct GbufferFeatures {
    pub phong: bool,
    pub ggx: bool,
    pub emission: bool,
    pub textures: bool,
    pub bump: bool,
    pub dissolve: bool,
    /// MTL `map_Pr`, `map_Pm` or `map_Ke`.
    pub pbr_maps: bool,
    /// Motion vectors (moving objects under TAA).
    pub motion: bool,
}

impl GbufferPass {
    /// The specular and emission targets, GGX shading, texture sampling, bump mapping and
    /// dissolve are compiled in only for scenes that have them (specialization constants).
    pub fn new(ctx: &Context, features: GbufferFeatures) -> Result<Self, VkError> {
        let f = features;
        let has_lobe = f.phong || f.ggx;
        let mut colors = vec![GBUFFER_COLOR, GBUFFER_COLOR];
        let extra = usize::from(has_lobe) + usize::from(f.emission);
        colors.resize(2 + extra, GBUFFER_COLOR);
        if f.motion {
            colors.push(MOTION_FORMAT);
        }
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: "gbuffer.vert".into(),
            geometry: None,
            fragment: "gbuffer.frag".into(),
            push: crate::vk::PushLayout::of::<GpuGbufferPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: vertex_attributes(),
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: colors,
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            spec: vec![
                (0, u32::from(f.phong)),
                (1, u32::from(f.textures)),
                (2, u32::from(f.bump)),
                (3, u32::from(f.dissolve)),
                (4, u32::from(f.ggx)),
                (5, u32::from(f.emission)),
                (6, u32::from(f.pbr_maps)),
                (7, u32::from(f.motion)),
            ],
        })?;
        Ok(Self {
            pipeline,
            has_lobe,
            has_emission: f.emission,
            has_motion: f.motion,
        })
    }

    pub fn declare(&self, g: &mut RenderGraph, scene: &SceneInputs, w: u32, h: u32) -> Gbuffer {
        let out = Gbuffer {
            albedo: g.create_image(ImageDesc::new_2d("gbuffer albedo", GBUFFER_COLOR, w, h)),
            normal: g.create_image(ImageDesc::new_2d("gbuffer normal", GBUFFER_COLOR, w, h)),
            specular: self.has_lobe.then(|| {
                g.create_image(ImageDesc::new_2d("gbuffer specular", GBUFFER_COLOR, w, h))
            }),
            emission: self.has_emission.then(|| {
                g.create_image(ImageDesc::new_2d("gbuffer emission", GBUFFER_COLOR, w, h))
            }),
            motion: self
                .has_motion
                .then(|| g.create_image(ImageDesc::new_2d("gbuffer motion", MOTION_FORMAT, w, h))),
            depth: g.create_image(ImageDesc::new_2d("gbuffer depth", DEPTH, w, h)),
        };
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let textures = scene.textures.clone();
        let placeholder = scene.placeholder();
        let sampler = scene.texture_sampler;
        let clear = Load::Clear([0.0; 4]);
        // Every texture a draw may bind (the placeholder, for draws without one, among them).
        let choices = textures.clone();
        let mut pass = g
            .add_pass("gbuffer")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(Shader::Fragment))
            .bind_one_of_sampled(2, choices.clone(), sampler, Shader::Fragment)
            .bind_one_of_sampled(3, choices.clone(), sampler, Shader::Fragment)
            .bind(
                4,
                scene.materials_pbr,
                Access::StorageRead(Shader::Fragment),
            )
            .bind_one_of_sampled(5, choices.clone(), sampler, Shader::Fragment)
            .bind_one_of_sampled(6, choices.clone(), sampler, Shader::Fragment)
            .bind_one_of_sampled(7, choices, sampler, Shader::Fragment)
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .color(out.albedo, clear)
            .color(out.normal, clear);
        // In location order: the lobe, the emission, the motion (gbuffer.frag).
        for extra in [out.specular, out.emission, out.motion]
            .into_iter()
            .flatten()
        {
            pass = pass.color(extra, clear);
        }
        pass = pass.depth(out.depth, Load::ClearDepth(1.0));
        pass.record(move |ctx| {
            ctx.begin_rendering();
            // A material's texture (or bump map), or the placeholder when it has none.
            let texture = |t: Option<usize>| {
                t.and_then(|i| textures.get(i).copied())
                    .unwrap_or(placeholder)
            };
            // Bindings 2 to 7: albedo, bump, roughness, metallic and emission maps.
            let maps = |d: Option<&super::scene_gpu::Draw>| {
                let [r, m, e] = d.map_or([None; 3], |d| d.pbr_maps);
                let (t, b) = d.map_or((None, None), |d| (d.texture, d.bump));
                [(2, t), (3, b), (5, r), (6, m), (7, e)].map(|(i, t)| (i, texture(t)))
            };
            ctx.bind_with(&pipe, &maps(None));
            ctx.bind_vertex_buffer(vertices);
            ctx.bind_index_buffer(indices);
            if let Ok(lists) = draws.read() {
                let mut bound = (None, None, [None; 3]);
                for d in &lists.camera {
                    if (d.texture, d.bump, d.pbr_maps) != bound {
                        ctx.push_with(&pipe, &maps(Some(d)));
                        bound = (d.texture, d.bump, d.pbr_maps);
                    }
                    let push = GpuGbufferPush::of(d);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd
                        .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                }
            }
            ctx.cmd.end_rendering();
        });
        out
    }
}

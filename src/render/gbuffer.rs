//! `gbuffer`: albedo, normal, (Phong or GGX scenes) specular lobe, (scenes with emitters)
//! emission, and depth of the camera view (`glsl/gbuffer.{vert,frag}`). Textures, bump maps and
//! the MTL PBR maps (roughness, metallic, emission) are chosen per draw among the declared ones
//! (`.bind_one_of_sampled`).

use super::scene_gpu::{vertex_attributes, SceneInputs};
use super::{DEPTH, GBUFFER_COLOR};
use crate::graph::{Access, BufferHandle, ImageHandle, Load, RenderGraph, Shader};
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

impl Gbuffer {
    /// One eye of a two-layer (multiview) G-buffer: each image's layer `eye`.
    pub fn eye(&self, g: &mut RenderGraph, eye: u32) -> Gbuffer {
        Gbuffer {
            albedo: g.layer(self.albedo, eye),
            normal: g.layer(self.normal, eye),
            specular: self.specular.map(|i| g.layer(i, eye)),
            emission: self.emission.map(|i| g.layer(i, eye)),
            motion: self.motion.map(|i| g.layer(i, eye)),
            depth: g.layer(self.depth, eye),
        }
    }
}

/// Views of the multiview G-buffer: left eye (layer 0) and right eye (layer 1).
const STEREO_VIEW_MASK: u32 = 0b11;

/// Which views the G-buffer draws, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GbufferViews {
    /// One camera, one-layer images.
    Mono,
    /// Both stereo eyes into two-layer images: one `gbuffer` pass per eye into its layer.
    PerEye,
    /// Both stereo eyes into two-layer images in one Vulkan multiview pass
    /// (`gbuffer_multiview`: view i into layer i).
    Multiview,
}

pub struct GbufferPass {
    pipeline: GraphicsPipeline,
    /// Instances per draw: 2 on a multiview path whose driver has
    /// [`super::multiview::MultiviewDefect`] (instance 0 flushes the driver's batch, instance 1
    /// is the mesh: `gbuffer_vert.glsl`, `FLUSH_INSTANCE`), else 1.
    instances: u32,
    /// The scene has Phong or GGX materials.
    has_lobe: bool,
    has_emission: bool,
    views: GbufferViews,
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
    /// Per-texel alpha (a cutout or blend map, `scene::AlphaMap`).
    pub alpha_maps: bool,
}

impl GbufferPass {
    /// The specular and emission targets, GGX shading, texture sampling, bump mapping and
    /// dissolve are compiled in only for scenes that have them (specialization constants).
    ///
    /// With [`GbufferViews::Multiview`] the pipeline is `gbuffer_multiview.{vert,frag}`'s,
    /// which draws both stereo eyes in one pass (the right eye's frame constants at binding 8).
    pub fn new(
        ctx: &Context,
        features: GbufferFeatures,
        views: GbufferViews,
    ) -> Result<Self, VkError> {
        let multiview = views == GbufferViews::Multiview;
        let defect =
            super::multiview::MultiviewDefect::of(ctx.info.driver_id, &ctx.info.driver_info);
        // The flushing instance relies on this pipeline's triangles needing no stage of the
        // draw module's primitive pipeline except clipping (filled polygons, no depth bias,
        // no cull distances), so an unclipped instance is emitted directly.
        let flush_instance = multiview && defect.is_some();
        let f = features;
        let has_lobe = f.phong || f.ggx;
        let mut colors = vec![GBUFFER_COLOR, GBUFFER_COLOR];
        let extra = usize::from(has_lobe) + usize::from(f.emission);
        colors.resize(2 + extra, GBUFFER_COLOR);
        if f.motion {
            colors.push(MOTION_FORMAT);
        }
        let stem = match multiview {
            true => "gbuffer_multiview",
            false => "gbuffer",
        };
        let mut spec = crate::spec_constants![
            HAS_PHONG = f.phong,
            HAS_TEXTURES = f.textures,
            HAS_BUMP = f.bump,
            HAS_DISSOLVE = f.dissolve,
            HAS_GGX = f.ggx,
            HAS_EMISSION = f.emission,
            HAS_PBR_MAPS = f.pbr_maps,
            HAS_MOTION = f.motion,
            HAS_ALPHA_MAP = f.alpha_maps,
        ]
        .to_vec();
        if multiview {
            spec.extend(crate::spec_constants![FLUSH_INSTANCE = flush_instance]);
        }
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: format!("{stem}.vert"),
            geometry: None,
            fragment: format!("{stem}.frag"),
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
            view_mask: if multiview { STEREO_VIEW_MASK } else { 0 },
            spec,
        })?;
        Ok(Self {
            pipeline,
            instances: if flush_instance { 2 } else { 1 },
            has_lobe,
            has_emission: f.emission,
            views,
            has_motion: f.motion,
        })
    }

    /// Declares the pass; for stereo every image has two layers, one per eye
    /// ([`Gbuffer::eye`]), and `scene.frame_right` must be present.
    pub fn declare(&self, g: &mut RenderGraph, scene: &SceneInputs, w: u32, h: u32) -> Gbuffer {
        let stereo = self.views != GbufferViews::Mono;
        let mut image = |name: &str, format| {
            let desc = ImageDesc::new_2d(name, format, w, h);
            g.create_image(if stereo { desc.with_layers(2) } else { desc })
        };
        let out = Gbuffer {
            albedo: image("gbuffer albedo", GBUFFER_COLOR),
            normal: image("gbuffer normal", GBUFFER_COLOR),
            specular: self
                .has_lobe
                .then(|| image("gbuffer specular", GBUFFER_COLOR)),
            emission: self
                .has_emission
                .then(|| image("gbuffer emission", GBUFFER_COLOR)),
            motion: self
                .has_motion
                .then(|| image("gbuffer motion", MOTION_FORMAT)),
            depth: image("gbuffer depth", DEPTH),
        };
        let right = scene.frame_right.unwrap_or(scene.frame);
        match self.views {
            GbufferViews::Mono => self.add_pass(g, scene, &out, (scene.frame, None)),
            GbufferViews::Multiview => self.add_pass(g, scene, &out, (scene.frame, Some(right))),
            GbufferViews::PerEye => {
                for (eye, frame) in [(0, scene.frame), (1, right)] {
                    let targets = out.eye(g, eye);
                    if eye == 1 {
                        g.set_pass_suffix(super::multiview::RIGHT_EYE_SUFFIX);
                    }
                    self.add_pass(g, scene, &targets, (frame, None));
                    g.set_pass_suffix("");
                }
            }
        }
        out
    }

    /// Declares one pass drawing the camera's draw list into `out` with the frame constants
    /// `frame`; with `right`, a multiview pass drawing the right eye too.
    fn add_pass(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        out: &Gbuffer,
        (frame, right): (BufferHandle, Option<BufferHandle>),
    ) {
        let multiview = right.is_some();
        let pipe = *self.pipeline;
        let instances = self.instances;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let textures = scene.textures.clone();
        let placeholder = scene.placeholder();
        let sampler = scene.texture_sampler;
        let clear = Load::Clear([0.0; 4]);
        // Every texture a draw may bind (the placeholder, for draws without one, among them).
        let choices = textures.clone();
        let mut pass = g
            .add_pass(if multiview {
                "gbuffer_multiview"
            } else {
                "gbuffer"
            })
            .pipeline(&pipe)
            .bind(0, frame, Access::StorageRead(Shader::Graphics))
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
        if let Some(right) = right {
            pass = pass
                .bind(8, right, Access::StorageRead(Shader::Graphics))
                .view_mask(STEREO_VIEW_MASK);
        }
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
                    ctx.cmd.draw_indexed_instanced(
                        d.index_count,
                        instances,
                        d.first_index,
                        d.vertex_offset,
                    );
                }
            }
            ctx.cmd.end_rendering();
        });
    }
}

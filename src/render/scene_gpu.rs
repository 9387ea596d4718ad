//! The scene on the GPU, shared by the frame's passes: one vertex and one index buffer, the
//! materials, the textures, the per-slot frame constants, and the culled draw lists.
//!
//! [`SceneGpu::import`] brings these into a graph as [`SceneInputs`]: read-only resources the
//! passes declare like any other, so the graph sees every use.

use super::gpu::{GpuFrame, GpuMaterial, GpuMaterialPbr, GpuVertex};
use super::{textures, RenderError};
use crate::graph::{Access, BufferHandle, ImageHandle, PassContext, RenderGraph, Shader};
use crate::scene::{Aabb, BumpKind, Scene};
use crate::vk::{
    vk, Buffer, BufferDesc, Context, Image, MemoryLocation, PipelineHandle, MAX_FRAMES_IN_FLIGHT,
};
use glam::{Mat4, Vec3};
use std::sync::{Arc, RwLock};

/// Meters of height per unit of a height (bump) map, times the MTL `-bm` multiplier: MTL has
/// no unit for heights.
const BUMP_SCALE_M: f32 = 0.01;

/// One indexed draw of a submesh of an object.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
    pub material: u32,
    /// Index into the scene's textures (the albedo map of the material).
    pub texture: Option<usize>,
    /// Index into the scene's textures of the material's bump or normal map.
    pub bump: Option<usize>,
    /// Indices into the scene's textures of the material's roughness, metallic and emission
    /// maps ([`crate::scene::PbrMaps::as_array`]).
    pub pbr_maps: [Option<usize>; 3],
    /// The object drawn (its transform and, for OBJ sequences, its frame follow the scene
    /// time), the submesh, and the mesh's local box.
    pub object: usize,
    pub submesh: usize,
    pub local_aabb: Aabb,
    pub model: Mat4,
    /// The model matrix of the previous frame written (motion vectors; `model` while they
    /// are off, in the first frame, and for objects that do not move).
    pub prev_model: Mat4,
    pub aabb: Aabb,
    /// The material's opacity (MTL `d`) is 1.
    pub opaque: bool,
}

/// Draw lists after culling, read by the recording closures.
#[derive(Clone, Debug, Default)]
pub struct DrawLists {
    /// What the G-buffer draws: every visible draw, or only the opaque ones when transparent
    /// surfaces are drawn by the transparency lists ([`SceneGpu::split_transparent`]).
    pub camera: Vec<Draw>,
    /// The visible draws of materials with d < 1 when they are split off (`oit_gather`).
    pub transparent: Vec<Draw>,
    /// Per shadow view (the lights' own views, which the light maps also draw).
    pub shadow: Vec<Vec<Draw>>,
    /// Per cascade view (`light::cascade`), after the shadow views: only the shadow maps
    /// draw them.
    pub cascades: Vec<Vec<Draw>>,
}

/// The scene's GPU resources.
pub struct SceneGpu {
    vertices: Buffer,
    indices: Buffer,
    materials: Buffer,
    /// `GpuMaterialPbr` per material.
    materials_pbr: Buffer,
    /// `MAX_FRAMES_IN_FLIGHT` copies of `GpuFrame`, `frame_stride` bytes apart.
    frame: Buffer,
    frame_stride: u64,
    /// The right eye's frame constants (same layout), only in a one-frame stereo renderer
    /// ([`SceneGpu::enable_right_eye`]); `frame` then holds the left eye's.
    frame_right: Option<Buffer>,
    /// Textures of the scene (a placeholder where a texture is unused), then a 1x1 white
    /// placeholder (always last).
    textures: Vec<Image>,
    texture_sampler: crate::vk::Sampler,
    /// Bilinear and repeating, without anisotropy: the environment map's sampler. Anisotropic
    /// filtering takes its footprint from the derivatives of the lookup coordinate between
    /// neighbouring invocations, which compute shaders do not define: the rays of neighbouring
    /// pixels point anywhere, and on lavapipe their lookups came back blurred over many texels
    /// (a 2 × 2-texel sun read at 19 to 94 where its bilinear value is 300 to 1000), so the map
    /// a ray saw depended on its neighbours' rays.
    environment_sampler: crate::vk::Sampler,
    /// The `[environment]` map (RGBA32F, linear radiance before its scale), if it is one.
    environment_map: Option<Image>,
    /// The map's importance-sampling tables (`scene::environment::EnvironmentCdf`), read by
    /// the passes that sample it (`gi.env_sampling`).
    environment_cdf: Option<Buffer>,
    pub draws: Arc<RwLock<DrawLists>>,
    pub all_draws: Vec<Draw>,
    /// Draws of materials with d < 1 leave the G-buffer's list for `transparent`.
    pub split_transparent: bool,
    /// Vertex and index offsets of every mesh in the shared buffers.
    mesh_base: Vec<(i32, u32)>,
    /// Motion vectors are drawn: [`SceneGpu::advance_motion`] keeps each draw's previous
    /// model matrix.
    pub motion: bool,
    /// Per object, its model matrix in the last frame written (`None`: none yet).
    written_models: Vec<Option<Mat4>>,
}

/// The scene's resources imported into one graph.
#[derive(Clone)]
pub struct SceneInputs {
    /// Frame constants (`GpuFrame`), one window per frame slot.
    pub frame: BufferHandle,
    /// The right eye's frame constants, in a one-frame stereo renderer.
    pub frame_right: Option<BufferHandle>,
    pub vertices: BufferHandle,
    pub indices: BufferHandle,
    pub materials: BufferHandle,
    /// GGX parameters and emission per material (`GpuMaterialPbr`).
    pub materials_pbr: BufferHandle,
    /// The scene's textures, the placeholder last.
    pub textures: Vec<ImageHandle>,
    /// Bilinear, repeating and anisotropic: the textures' sampler.
    pub texture_sampler: vk::Sampler,
    /// Bilinear and repeating, without anisotropy: the environment map's sampler.
    pub environment_sampler: vk::Sampler,
    /// The environment map (`glsl/include/environment.glsl`), in scenes lit by one.
    pub environment_map: Option<ImageHandle>,
    /// Its importance-sampling tables (`glsl/include/environment_sampling.glsl`).
    pub environment_cdf: Option<BufferHandle>,
    pub draws: Arc<RwLock<DrawLists>>,
}

impl SceneInputs {
    /// The placeholder texture's handle (bound where a draw has no map).
    pub fn placeholder(&self) -> ImageHandle {
        self.textures[self.textures.len() - 1]
    }
}

impl SceneGpu {
    pub fn new(ctx: &Context, scene: &Scene, time_s: f32) -> Result<Self, RenderError> {
        let geometry = upload_geometry(ctx, scene, time_s)?;
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| GpuMaterial {
                albedo: [m.albedo.x, m.albedo.y, m.albedo.z, m.opacity],
                specular: [m.specular.x, m.specular.y, m.specular.z, m.shininess],
                flags: [
                    u32::from(m.albedo_texture.is_some()),
                    match (m.bump_texture, m.bump_kind) {
                        (None, _) => 0,
                        (Some(_), BumpKind::Height) => 1,
                        (Some(_), BumpKind::TangentNormal) => 2,
                    },
                    (BUMP_SCALE_M * m.bump_scale).to_bits(),
                    alpha_map_flag(m),
                ],
            })
            .collect();
        let materials = ctx.upload_buffer(
            "materials",
            bytemuck::cast_slice(&materials),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let materials_pbr: Vec<GpuMaterialPbr> = scene
            .materials
            .iter()
            .map(|m| {
                let ggx = m
                    .ggx
                    .map_or([0.0; 4], |g| [g.roughness, g.metallic, 1.0, 0.0]);
                let e = m.emission;
                let [r, metal, em] = m.pbr_maps.as_array().map(|t| u32::from(t.is_some()));
                GpuMaterialPbr {
                    ggx,
                    emission: [e.x, e.y, e.z, 0.0],
                    maps: [r, metal, em, 0],
                }
            })
            .collect();
        let materials_pbr = ctx.upload_buffer(
            "materials pbr",
            bytemuck::cast_slice(&materials_pbr),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let frame_stride = (std::mem::size_of::<GpuFrame>() as u64).next_multiple_of(256);
        let frame = ctx.create_buffer(&BufferDesc {
            name: "frame constants".into(),
            size_bytes: frame_stride * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let mut textures = Vec::new();
        for (i, t) in scene.textures.iter().enumerate() {
            let used = scene.materials.iter().any(|m| {
                m.draw_texture() == Some(i)
                    || m.bump_texture == Some(i)
                    || m.pbr_maps.as_array().contains(&Some(i))
            });
            textures.push(if used {
                textures::upload_texture(ctx, t, &format!("texture {}", t.path.display()))?
            } else {
                textures::upload_texture(ctx, &placeholder_texture(), "unused texture slot")?
            });
        }
        textures.push(textures::upload_texture(
            ctx,
            &placeholder_texture(),
            "texture placeholder",
        )?);
        let texture_sampler =
            ctx.create_sampler_with(vk::Filter::LINEAR, true, vk::SamplerAddressMode::REPEAT)?;
        let environment_sampler =
            ctx.create_sampler_with(vk::Filter::LINEAR, false, vk::SamplerAddressMode::REPEAT)?;
        let environment_map = match scene.environment.as_ref().and_then(|e| e.map()) {
            Some(m) => Some(ctx.upload_image(
                &crate::vk::ImageDesc::new_2d(
                    &format!("environment {}", m.path.display()),
                    vk::Format::R32G32B32A32_SFLOAT,
                    m.width,
                    m.height,
                ),
                &[bytemuck::cast_slice(&m.texels).to_vec()],
            )?),
            _ => None,
        };
        let environment_cdf = match scene
            .environment
            .as_ref()
            .and_then(|e| e.map())
            .and_then(crate::scene::environment::EnvironmentCdf::new)
        {
            Some(cdf) => Some(ctx.upload_buffer(
                "environment cdf",
                &cdf.to_gpu_bytes(),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            None => None,
        };
        Ok(Self {
            vertices: geometry.vertices,
            indices: geometry.indices,
            materials,
            materials_pbr,
            frame,
            frame_stride,
            frame_right: None,
            textures,
            texture_sampler,
            environment_sampler,
            environment_map,
            environment_cdf,
            draws: Arc::new(RwLock::new(DrawLists::default())),
            all_draws: geometry.draws,
            split_transparent: false,
            mesh_base: geometry.mesh_base,
            motion: false,
            written_models: Vec::new(),
        })
    }

    /// Imports the scene's resources into `g`.
    pub fn import(&self, g: &mut RenderGraph) -> SceneInputs {
        let per_slot = |g: &mut RenderGraph, b: &Buffer| {
            g.import_buffer_per_slot(
                b,
                self.frame_stride,
                std::mem::size_of::<GpuFrame>() as u64,
                Access::StorageRead(Shader::Compute),
            )
        };
        SceneInputs {
            frame: per_slot(g, &self.frame),
            frame_right: self.frame_right.as_ref().map(|b| per_slot(g, b)),
            vertices: g.import_buffer(&self.vertices, Access::VertexBuffer),
            indices: g.import_buffer(&self.indices, Access::IndexBuffer),
            materials: g.import_buffer(&self.materials, Access::StorageRead(Shader::Compute)),
            materials_pbr: g
                .import_buffer(&self.materials_pbr, Access::StorageRead(Shader::Compute)),
            textures: self
                .textures
                .iter()
                .map(|t| g.import_image(t, Access::Sampled(Shader::Fragment)))
                .collect(),
            texture_sampler: self.texture_sampler.raw,
            environment_sampler: self.environment_sampler.raw,
            environment_map: self
                .environment_map
                .as_ref()
                .map(|m| g.import_image(m, Access::Sampled(Shader::Compute))),
            environment_cdf: self
                .environment_cdf
                .as_ref()
                .map(|b| g.import_buffer(b, Access::StorageRead(Shader::Compute))),
            draws: self.draws.clone(),
        }
    }

    /// Moves animated objects to the scene time `time_s` (keyframes move them, OBJ sequences
    /// switch to the frame's mesh; frames share topology, so only the buffer offsets change)
    /// and dynamic ones to their transform in `scene` (the viewer's editor moves them), then
    /// culls the draw lists against the camera (the union of `view_projs`: both eyes of a
    /// one-frame stereo renderer), each shadow view and each cascade view.
    pub fn update_draws(
        &mut self,
        scene: &Scene,
        time_s: f32,
        view_projs: &[Mat4],
        (shadow_views, cascade_views): (&[crate::light::ShadowView], &[crate::light::ShadowView]),
    ) {
        for d in &mut self.all_draws {
            let moving = |o: &&crate::scene::Object| o.is_animated() || o.dynamic;
            let Some(o) = scene.objects.get(d.object).filter(moving) else {
                continue;
            };
            let mesh_index = o.mesh_at(time_s);
            if let (Some(mesh), Some(&(vbase, ibase))) =
                (scene.meshes.get(mesh_index), self.mesh_base.get(mesh_index))
            {
                if let Some(sub) = mesh.submeshes.get(d.submesh) {
                    d.first_index = ibase + sub.first_index;
                    d.index_count = sub.index_count;
                    d.vertex_offset = vbase;
                    d.local_aabb = mesh.aabb;
                }
            }
            d.model = o.transform_at(time_s);
            d.aabb = d.local_aabb.transformed(&d.model);
        }
        let culled = |views: &[crate::light::ShadowView]| -> Vec<Vec<Draw>> {
            views
                .iter()
                .map(|v| {
                    self.all_draws
                        .iter()
                        .copied()
                        .filter(|d| v.may_see(&d.aabb))
                        .collect()
                })
                .collect()
        };
        let visible: Vec<Draw> = self
            .all_draws
            .iter()
            .copied()
            .filter(|d| {
                view_projs
                    .iter()
                    .any(|vp| crate::scene::aabb_visible(vp, &d.aabb))
            })
            .collect();
        let split = self.split_transparent;
        let (camera, transparent) = visible.into_iter().partition(|d| d.opaque || !split);
        let lists = DrawLists {
            camera,
            transparent,
            shadow: culled(shadow_views),
            cascades: culled(cascade_views),
        };
        if let Ok(mut d) = self.draws.write() {
            *d = lists;
        }
    }

    /// Starts a frame for the motion vectors: every listed draw's `prev_model` becomes its
    /// object's model in the last frame written (its own model in the first frame), then the
    /// current models are remembered for the next frame. Per frame written, not per
    /// [`SceneGpu::update_draws`], so a frame rendered without moving anything has no motion.
    pub fn advance_motion(&mut self) {
        let written = &mut self.written_models;
        if let Ok(mut lists) = self.draws.write() {
            let DrawLists {
                camera,
                transparent,
                ..
            } = &mut *lists;
            for d in camera.iter_mut().chain(transparent.iter_mut()) {
                d.prev_model = written.get(d.object).copied().flatten().unwrap_or(d.model);
            }
        }
        for d in &self.all_draws {
            if written.len() <= d.object {
                written.resize(d.object + 1, None);
            }
            written[d.object] = Some(d.model);
        }
    }

    /// Writes the frame constants of frame slot `slot` (after the slot's fence).
    pub fn write_frame(&mut self, slot: usize, frame: &GpuFrame) {
        write_slot(&mut self.frame, self.frame_stride, slot, frame);
    }

    /// Gives the scene a second set of frame constants, the right eye's, for a renderer that
    /// draws both stereo eyes in one pass.
    pub fn enable_right_eye(&mut self, ctx: &Context) -> Result<(), RenderError> {
        self.frame_right = Some(ctx.create_buffer(&BufferDesc {
            name: "frame constants (right eye)".into(),
            size_bytes: self.frame_stride * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?);
        Ok(())
    }

    /// Writes the right eye's frame constants of slot `slot` (see [`Self::enable_right_eye`]).
    pub fn write_frame_right(&mut self, slot: usize, frame: &GpuFrame) {
        if let Some(b) = &mut self.frame_right {
            write_slot(b, self.frame_stride, slot, frame);
        }
    }
}

/// Writes `frame` into slot `slot`'s window of a per-slot frame-constants buffer.
fn write_slot(buffer: &mut Buffer, stride: u64, slot: usize, frame: &GpuFrame) {
    let offset = (slot as u64 * stride) as usize;
    let bytes = bytemuck::bytes_of(frame);
    if let Some(m) = buffer.mapped_mut() {
        m[offset..offset + bytes.len()].copy_from_slice(bytes);
    }
}

/// Push constants of the passes that draw every shadow view's draw list (`shadow_depth.vert`,
/// `light_map.vert`): the model matrix, the shadow view the geometry shader routes the draw
/// to, the material (dissolve coverage), and the attachment's first layer (a pass that draws
/// one view into one layer of the array, [`record_one_view`]; 0 otherwise).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuShadowViewPush {
    pub model: [f32; 16],
    pub view: u32,
    pub material: u32,
    pub layer_base: u32,
    pub _pad: u32,
}

crate::push_constants!(GpuShadowViewPush {
    model,
    view,
    material,
    layer_base,
    _pad
});

/// Records a pass that draws every shadow view's draw list into its declared (layered)
/// attachments with `pipe`, calling `per_draw` before each draw (after the pipeline is bound;
/// the light maps push the draw's textures there): the light-map pass (the shadow-depth pass
/// also draws the cascades, [`record_shadow_and_cascade_views`]).
pub fn record_shadow_views(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    scene: (BufferHandle, BufferHandle),
    draws: &RwLock<DrawLists>,
    per_draw: &mut dyn FnMut(&Draw),
) {
    record_views(ctx, pipe, scene, draws, false, per_draw);
}

/// [`record_shadow_views`], then the cascade views' lists into the layers after them.
pub fn record_shadow_and_cascade_views(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    scene: (BufferHandle, BufferHandle),
    draws: &RwLock<DrawLists>,
    per_draw: &mut dyn FnMut(&Draw),
) {
    record_views(ctx, pipe, scene, draws, true, per_draw);
}

/// Hashes into `key` what [`record_shadow_views`] draws of `lists` (per view: its draws'
/// ranges, model matrices and materials), so that a cache of the views' maps changes its key
/// exactly when the recorded draws change.
pub fn hash_view_draws<'a>(
    key: &mut crate::graph::KeyHasher,
    lists: impl Iterator<Item = &'a Vec<Draw>>,
) {
    for list in lists {
        key.u64(list.len() as u64);
        for d in list {
            key.bytes(bytemuck::cast_slice(&d.model.to_cols_array()))
                .u64(u64::from(d.first_index))
                .u64(u64::from(d.index_count))
                .u64(d.vertex_offset as u64)
                .u64(u64::from(d.material));
        }
    }
}

fn record_views(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    scene: (BufferHandle, BufferHandle),
    draws: &RwLock<DrawLists>,
    cascades: bool,
    per_draw: &mut dyn FnMut(&Draw),
) {
    render_draw_lists(ctx, pipe, scene, draws, |lists| {
        let cascade_lists = if cascades { &lists.cascades[..] } else { &[] };
        for (v, list) in lists.shadow.iter().chain(cascade_lists).enumerate() {
            draw_view(ctx, pipe, list, (v as u32, 0), per_draw);
        }
    });
}

/// The frame of every pass drawing the shadow views' lists: rendering into the pass's declared
/// attachments with `pipe` and the scene's vertex and index buffers bound, `record` drawing
/// from the lists.
fn render_draw_lists(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    scene: (BufferHandle, BufferHandle),
    draws: &RwLock<DrawLists>,
    record: impl FnOnce(&DrawLists),
) {
    ctx.begin_rendering();
    ctx.bind(pipe);
    ctx.bind_vertex_buffer(scene.0);
    ctx.bind_index_buffer(scene.1);
    if let Ok(lists) = draws.read() {
        record(&lists);
    }
    ctx.cmd.end_rendering();
}

/// `GpuMaterial::flags.w`: how the draw texture's alpha acts, as f32 bits (the shaders'
/// `alpha_map_discard`, glsl/include/alpha_map.glsl): 0 none, a cutoff in (0, 1] for a
/// cutout, −1 for per-texel opacity (blend).
pub fn alpha_map_flag(m: &crate::scene::Material) -> u32 {
    use crate::scene::{AlphaMap, AlphaMode};
    match m.alpha_map {
        None => 0,
        Some(AlphaMap {
            mode: AlphaMode::Cutout(c),
            ..
        }) => c.clamp(f32::MIN_POSITIVE, 1.0).to_bits(),
        Some(AlphaMap {
            mode: AlphaMode::Blend,
            ..
        }) => (-1.0f32).to_bits(),
    }
}

/// Records a pass that draws shadow view `view`'s list (a light's own view, then the cascades
/// after them, as [`record_shadow_and_cascade_views`] numbers them) into its declared
/// attachment, one layer of the shadow array viewed alone (so its draws land in layer 0 of
/// the attachment). A view the frame does not use (a dropped cascade) is only cleared.
pub fn record_one_view(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    scene: (BufferHandle, BufferHandle),
    draws: &RwLock<DrawLists>,
    view: u32,
    per_draw: &mut dyn FnMut(&Draw),
) {
    render_draw_lists(ctx, pipe, scene, draws, |lists| {
        if let Some(list) = lists
            .shadow
            .iter()
            .chain(&lists.cascades)
            .nth(view as usize)
        {
            draw_view(ctx, pipe, list, (view, view), per_draw);
        }
    });
}

/// Draws `list` into shadow view `view`, at attachment layer `view - layer_base`.
fn draw_view(
    ctx: &PassContext,
    pipe: &PipelineHandle,
    list: &[Draw],
    (view, layer_base): (u32, u32),
    per_draw: &mut dyn FnMut(&Draw),
) {
    for d in list {
        per_draw(d);
        let push = GpuShadowViewPush {
            model: d.model.to_cols_array(),
            view,
            material: d.material,
            layer_base,
            _pad: 0,
        };
        ctx.cmd.push_constants(pipe, bytemuck::bytes_of(&push));
        ctx.cmd
            .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
    }
}

/// The vertex layout every mesh pass reads: position, normal, uv.
pub fn vertex_attributes() -> Vec<(vk::Format, u32)> {
    vec![
        (
            vk::Format::R32G32B32_SFLOAT,
            std::mem::offset_of!(GpuVertex, position) as u32,
        ),
        (
            vk::Format::R32G32B32_SFLOAT,
            std::mem::offset_of!(GpuVertex, normal) as u32,
        ),
        (
            vk::Format::R32G32_SFLOAT,
            std::mem::offset_of!(GpuVertex, uv) as u32,
        ),
    ]
}

/// A 1x1 white texture bound where a draw has no albedo map.
fn placeholder_texture() -> crate::scene::TextureData {
    crate::scene::TextureData::new("placeholder".into(), 1, 1, vec![255; 4], true)
}

/// The scene's meshes on the GPU: one vertex and one index buffer, a draw per submesh of each
/// object, and each mesh's offsets in the buffers.
struct Geometry {
    vertices: Buffer,
    indices: Buffer,
    draws: Vec<Draw>,
    mesh_base: Vec<(i32, u32)>,
}

/// Uploads every mesh into one vertex and one index buffer; one draw per submesh of each
/// object at time `t_s`.
fn upload_geometry(ctx: &Context, scene: &Scene, t_s: f32) -> Result<Geometry, RenderError> {
    let mut vertices: Vec<GpuVertex> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut mesh_base = Vec::with_capacity(scene.meshes.len());
    for mesh in &scene.meshes {
        mesh_base.push((vertices.len() as i32, indices.len() as u32));
        for (i, p) in mesh.positions.iter().enumerate() {
            let n = mesh.normals.get(i).copied().unwrap_or(Vec3::Y);
            let uv = mesh
                .uvs
                .as_ref()
                .and_then(|u| u.get(i).copied())
                .unwrap_or_default();
            vertices.push(GpuVertex {
                position: p.to_array(),
                normal: n.to_array(),
                uv: uv.to_array(),
            });
        }
        indices.extend_from_slice(&mesh.indices);
    }
    if vertices.is_empty() || indices.is_empty() {
        return Err(RenderError::EmptyScene);
    }
    let mut draws = Vec::new();
    for (object_index, object) in scene.objects.iter().enumerate() {
        let mesh_index = object.mesh_at(t_s);
        let Some(mesh) = scene.meshes.get(mesh_index) else {
            continue;
        };
        let (vbase, ibase) = mesh_base[mesh_index];
        let model = object.transform_at(t_s);
        let aabb = mesh.aabb.transformed(&model);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let texture = scene.materials.get(material).and_then(|m| m.draw_texture());
            let bump = scene.materials.get(material).and_then(|m| m.bump_texture);
            let pbr_maps = scene
                .materials
                .get(material)
                .map_or([None; 3], |m| m.pbr_maps.as_array());
            draws.push(Draw {
                first_index: ibase + sub.first_index,
                index_count: sub.index_count,
                vertex_offset: vbase,
                material: material as u32,
                texture,
                bump,
                pbr_maps,
                object: object_index,
                submesh: si,
                local_aabb: mesh.aabb,
                model,
                prev_model: model,
                aabb,
                opaque: scene.materials.get(material).is_none_or(|m| m.is_opaque()),
            });
        }
    }
    let vertices = ctx.upload_buffer(
        "vertices",
        bytemuck::cast_slice(&vertices),
        vk::BufferUsageFlags::VERTEX_BUFFER,
    )?;
    let indices = ctx.upload_buffer(
        "indices",
        bytemuck::cast_slice(&indices),
        vk::BufferUsageFlags::INDEX_BUFFER,
    )?;
    Ok(Geometry {
        vertices,
        indices,
        draws,
        mesh_base,
    })
}

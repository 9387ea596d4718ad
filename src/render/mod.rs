//! The frame of voxgi: shadow maps → G-buffer → deferred direct light → tone mapping, with
//! read-back of the linear HDR radiance and the tone-mapped image.
//!
//! [`Renderer`] uploads a [`Scene`] once, owns the pipelines, and declares the frame as a
//! render graph; [`render_image`] runs one frame headless.

mod cull;
pub mod gpu;
mod textures;

pub use cull::aabb_visible;

use crate::eval::HdrImage;
use crate::graph::{Access, GraphError, GraphExecutor, ImageHandle, RenderGraph, Shader};
use crate::light::{shadow_views, PointShadow, ShadowSettings};
use crate::post::ToneMap;
use crate::scene::{BumpKind, Light, Scene};
use crate::vk::{
    vk, Attachment, Buffer, BufferDesc, Cmd, ComputePipeline, Context, Descriptor, FrameLoop,
    GraphicsPipeline, GraphicsPipelineDesc, ImageDesc, MemoryLocation, PassTiming, VkError,
    MAX_FRAMES_IN_FLIGHT,
};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};
use gpu::*;
use std::sync::{Arc, RwLock};

/// Errors of building or running a frame.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error("the scene has {0} lights; voxgi renders at most {MAX_LIGHTS}: remove some")]
    TooManyLights(usize),
    #[error("the scene's lights need {0} shadow-map views; at most {MAX_SHADOW_VIEWS} fit (a point light takes 6, or 2 with paraboloid shadows): remove some point lights or use --point-shadows paraboloid")]
    TooManyShadowViews(usize),
    #[error("image size {0}x{1} is invalid: width and height must be between 1 and 16384")]
    BadSize(u32, u32),
    #[error("the scene has no geometry to render: add an object")]
    EmptyScene,
    #[error("indirect light reads reflective light maps, which exist for cube shadow maps only: use --point-shadows cube with --gi")]
    GiNeedsCubeShadows,
    #[error(transparent)]
    Voxel(#[from] crate::voxel::gpu::GpuVoxelError),
}

/// What a frame renders.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Scene time (animation), seconds.
    pub time_s: f32,
    pub shadow: ShadowSettings,
    pub tonemap: ToneMap,
    /// Voxelize the scene every frame (`None`: direct light needs no voxels). Indirect light
    /// voxelizes with default settings when this is `None`.
    pub voxels: Option<crate::voxel::gpu::VoxelSettings>,
    /// Indirect light (method `None`: direct light only).
    pub gi: crate::gi::GiSettings,
    /// Show a voxel debug view instead of the lit image (voxelizes with the default
    /// [`crate::voxel::gpu::VoxelSettings`] when `voxels` is `None`).
    pub debug: Option<crate::voxel::debug_view::DebugSettings>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            time_s: 0.0,
            shadow: ShadowSettings::default(),
            tonemap: ToneMap::default(),
            voxels: None,
            gi: crate::gi::GiSettings::default(),
            debug: None,
        }
    }
}

/// The images a declared frame produces.
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    /// Linear radiance, RGBA32F.
    pub radiance: ImageHandle,
    /// Tone-mapped, sRGB-encoded values in RGBA8 UNORM.
    pub ldr: ImageHandle,
}

/// One indexed draw of a submesh of an object.
#[derive(Clone, Copy, Debug)]
struct Draw {
    first_index: u32,
    index_count: u32,
    vertex_offset: i32,
    material: u32,
    /// Index into the renderer's textures (the albedo map of the material).
    texture: Option<usize>,
    /// Index into the renderer's textures of the material's bump or normal map.
    bump: Option<usize>,
    /// The object drawn (its transform and, for OBJ sequences, its frame follow the scene
    /// time), the submesh, and the mesh's local box.
    object: usize,
    submesh: usize,
    local_aabb: crate::scene::Aabb,
    model: Mat4,
    aabb: crate::scene::Aabb,
}

/// Draw lists after culling, read by the recording closures.
#[derive(Clone, Debug, Default)]
struct DrawLists {
    camera: Vec<Draw>,
    /// Per shadow view.
    shadow: Vec<Vec<Draw>>,
}

struct Pipelines {
    gbuffer: GraphicsPipeline,
    shadow: GraphicsPipeline,
    deferred: ComputePipeline,
    tonemap: ComputePipeline,
}

/// A scene on the GPU with the pipelines of the direct-light frame.
pub struct Renderer {
    pub settings: RenderSettings,
    vertices: Buffer,
    indices: Buffer,
    materials: Buffer,
    /// `MAX_FRAMES_IN_FLIGHT` copies of `GpuFrame`, `frame_stride` bytes apart.
    frame: Buffer,
    frame_stride: u64,
    readback_hdr: Buffer,
    readback_ldr: Buffer,
    pipelines: Pipelines,
    sampler: vk::Sampler,
    /// Albedo textures of the scene, then a 1x1 white placeholder (always last).
    textures: Vec<crate::vk::Image>,
    texture_sampler: vk::Sampler,
    has_phong: bool,
    shadow_view_count: u32,
    draws: Arc<RwLock<DrawLists>>,
    all_draws: Vec<Draw>,
    /// Vertex and index offsets of every mesh in the shared buffers.
    mesh_base: Vec<(i32, u32)>,
    frame_data: GpuFrame,
    voxels: Option<crate::voxel::gpu::VoxelFrame>,
    /// Indirect-light passes and the light-map pipeline, when a GI method is on.
    gi: Option<(crate::gi::GiPasses, GraphicsPipeline)>,
    voxel_debug: Option<crate::voxel::debug_view::VoxelDebugPass>,
    atlas_view: Option<crate::voxel::atlas_view::AtlasViewPass>,
}

/// Meters of height per unit of a height (bump) map, times the MTL `-bm` multiplier: MTL has
/// no unit for heights.
const BUMP_SCALE_M: f32 = 0.01;

const GBUFFER_COLOR: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
const HDR: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Reflected radiance in the light maps. f32, not f16: light intensities from 1e-6 to 1e6 W/sr
/// (DESIGN.md, extremes) put it outside f16's range (max 65504, normal down to 6e-5); f16
/// lost 1.5% of the peak at 1e-6 and overflowed to Inf at 1e6 (tests/extremes.rs).
const LIGHT_MAP_RADIANCE: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

impl Renderer {
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        if settings.width == 0
            || settings.height == 0
            || settings.width > 16384
            || settings.height > 16384
        {
            return Err(RenderError::BadSize(settings.width, settings.height));
        }
        if scene.lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(scene.lights.len()));
        }
        let Geometry {
            vertices,
            indices,
            draws: all_draws,
            mesh_base,
        } = upload_geometry(ctx, scene, settings.time_s)?;
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
                    0,
                ],
            })
            .collect();
        let materials_buf = ctx.upload_buffer(
            "materials",
            bytemuck::cast_slice(&materials),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let has_phong = !scene.is_all_lambert();
        let frame_stride = (std::mem::size_of::<GpuFrame>() as u64).next_multiple_of(256);
        let frame = ctx.create_buffer(&BufferDesc {
            name: "frame constants".into(),
            size_bytes: frame_stride * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let readback_hdr = ctx.create_buffer(&BufferDesc {
            name: "readback hdr".into(),
            size_bytes: pixels * 16,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?;
        let readback_ldr = ctx.create_buffer(&BufferDesc {
            name: "readback ldr".into(),
            size_bytes: pixels * 4,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?;
        let has_textures = scene.has_albedo_textures();
        let mut textures = Vec::new();
        for (i, t) in scene.textures.iter().enumerate() {
            if scene
                .materials
                .iter()
                .any(|m| m.albedo_texture == Some(i) || m.bump_texture == Some(i))
            {
                textures.push(textures::upload_texture(
                    ctx,
                    t,
                    &format!("texture {}", t.path.display()),
                )?);
            } else {
                textures.push(textures::upload_texture(
                    ctx,
                    &placeholder_texture(),
                    "unused texture slot",
                )?);
            }
        }
        textures.push(textures::upload_texture(
            ctx,
            &placeholder_texture(),
            "texture placeholder",
        )?);
        let texture_sampler = ctx.create_sampler(vk::Filter::LINEAR, true)?;
        // Paraboloid maps write their depth per fragment, which costs the other maps their
        // early depth test: only scenes that have them pay for it.
        let paraboloid = settings.shadow.point_technique == PointShadow::DualParaboloid
            && scene
                .lights
                .iter()
                .any(|l| matches!(l, Light::Point { .. }));
        let pipelines = create_pipelines(
            ctx,
            has_phong,
            has_textures,
            scene.has_bump_maps(),
            scene.has_transparency(),
            paraboloid,
        )?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let gi_on = settings.gi.method != crate::gi::GiMethod::None;
        if gi_on
            && settings.shadow.point_technique == PointShadow::DualParaboloid
            && scene.has_point_lights()
        {
            return Err(RenderError::GiNeedsCubeShadows);
        }
        // The atlas view only needs the grid's voxel size, not a voxelization.
        let atlas_view_on = settings
            .debug
            .is_some_and(|d| d.view == crate::voxel::debug_view::DebugView::Atlas);
        let voxel_settings = settings.voxels.or(gi_on.then(Default::default)).or(settings
            .debug
            .filter(|_| !atlas_view_on)
            .map(|_| Default::default()));
        let mut voxels = match &voxel_settings {
            Some(v) => Some(crate::voxel::gpu::VoxelFrame::new(
                ctx,
                scene,
                settings.time_s,
                v,
            )?),
            None => None,
        };
        let gi = match (&mut voxels, gi_on) {
            (Some(v), true) => {
                // With the atlas voxelizer its points write the volumes (digest §3.4).
                let atlas_attributes = crate::gi::GiPasses::needs_attribute_volumes(&settings.gi)
                    && v.enable_attribute_volumes(ctx, scene)?;
                let passes = crate::gi::GiPasses::new(
                    ctx,
                    settings.gi,
                    &crate::gi::GiTarget {
                        scene,
                        time_s: settings.time_s,
                        grid: &v.voxels.grid,
                        shadow_resolution: settings.shadow.resolution,
                        size: (settings.width, settings.height),
                        has_phong,
                        atlas_attributes,
                    },
                )?;
                let light_map = create_light_map_pipeline(ctx, scene.has_transparency())?;
                Some((passes, light_map))
            }
            _ => None,
        };
        let atlas_view = match &settings.debug {
            Some(d) if atlas_view_on => {
                let grid = settings
                    .voxels
                    .unwrap_or_default()
                    .grid_for(scene, settings.time_s)
                    .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
                Some(crate::voxel::atlas_view::AtlasViewPass::new(
                    ctx,
                    scene,
                    settings.time_s,
                    &grid,
                    d.object,
                )?)
            }
            _ => None,
        };
        let voxel_debug = match (&settings.debug, &mut voxels) {
            (Some(d), Some(v)) if !atlas_view_on => {
                // With the atlas voxelizer its points write the albedo the view shows.
                if d.view == crate::voxel::debug_view::DebugView::Albedo {
                    v.enable_attribute_volumes(ctx, scene)?;
                }
                Some(crate::voxel::debug_view::VoxelDebugPass::new(
                    ctx,
                    scene,
                    settings.time_s,
                    settings.width as f32 / settings.height as f32,
                    d,
                    v,
                )?)
            }
            _ => None,
        };
        let mut r = Self {
            settings,
            vertices,
            indices,
            materials: materials_buf,
            frame,
            frame_stride,
            readback_hdr,
            readback_ldr,
            pipelines,
            sampler,
            textures,
            texture_sampler,
            has_phong,
            shadow_view_count: 0,
            draws: Arc::new(RwLock::new(DrawLists::default())),
            all_draws,
            mesh_base,
            frame_data: GpuFrame::zeroed(),
            voxels,
            gi,
            voxel_debug,
            atlas_view,
        };
        r.prepare(scene)?;
        Ok(r)
    }

    /// Computes frame constants, shadow views and culled draw lists for the scene's camera and
    /// lights and `settings`. Call again after changing them (the viewer does, every frame);
    /// a new size, shadow resolution or tone map also needs a new graph.
    pub fn prepare(&mut self, scene: &Scene) -> Result<(), RenderError> {
        let s = &self.settings;
        let (views, per_light) = shadow_views(scene, s.time_s, &s.shadow);
        if views.len() > MAX_SHADOW_VIEWS {
            return Err(RenderError::TooManyShadowViews(views.len()));
        }
        let aspect = s.width as f32 / s.height as f32;
        let view_proj = scene.camera.view_proj(aspect);
        let mut f = GpuFrame::zeroed();
        f.view_proj = view_proj.to_cols_array();
        f.inv_view_proj = view_proj.inverse().to_cols_array();
        f.camera_position = scene.camera.position.extend(1.0).to_array();
        f.counts = [
            scene.lights.len() as u32,
            views.len() as u32,
            s.width,
            s.height,
        ];
        f.shadow = [
            s.shadow.bias_texels,
            s.shadow.slope_bias_texels,
            s.shadow.normal_offset_texels,
            s.shadow.pcf_radius as f32,
        ];
        for (i, light) in scene.lights.iter().enumerate() {
            f.lights[i] = gpu_light(light, per_light[i].first, per_light[i].count);
        }
        for (i, v) in views.iter().enumerate() {
            f.shadow_views[i] = GpuShadowView {
                view_proj: v.view_proj.to_cols_array(),
                params: [v.texel_footprint, v.projection.gpu_code(), v.near, v.far],
                axis: v.axis.extend(0.0).to_array(),
            };
        }
        // Accumulated indirect light is valid only while camera, lights and settings stay.
        if let Some((gi, _)) = &self.gi {
            if bytemuck::bytes_of(&f) != bytemuck::bytes_of(&self.frame_data) {
                gi.reset();
            }
        }
        self.frame_data = f;
        self.shadow_view_count = views.len() as u32;
        // Animated objects follow the scene time: keyframes move them, OBJ sequences switch
        // to the frame's mesh (frames share topology, so only the buffer offsets change).
        for d in &mut self.all_draws {
            let Some(o) = scene.objects.get(d.object).filter(|o| o.is_animated()) else {
                continue;
            };
            let mesh_index = o.mesh_at(s.time_s);
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
            d.model = o.transform_at(s.time_s);
            d.aabb = d.local_aabb.transformed(&d.model);
        }
        let lists = DrawLists {
            camera: self
                .all_draws
                .iter()
                .copied()
                .filter(|d| aabb_visible(&view_proj, &d.aabb))
                .collect(),
            shadow: views
                .iter()
                .map(|v| {
                    self.all_draws
                        .iter()
                        .copied()
                        .filter(|d| v.may_see(&d.aabb))
                        .collect()
                })
                .collect(),
        };
        if let Ok(mut d) = self.draws.write() {
            *d = lists;
        }
        Ok(())
    }

    /// Writes the frame constants of frame slot `slot` (call after the slot's fence), and the
    /// dynamic objects' voxels at `settings.time_s`.
    pub fn write_frame(&mut self, slot: usize) {
        let mut attributes_moved = false;
        if let Some(v) = &mut self.voxels {
            if let Err(e) = v.update(self.settings.time_s, slot) {
                log::warn!("dynamic objects not re-voxelized: {e}");
            }
            attributes_moved = v.attributes_moved();
        }
        if let Some((gi, _)) = &mut self.gi {
            gi.update_dynamic(self.settings.time_s, slot);
            if attributes_moved {
                gi.reset();
            }
            gi.advance();
        }
        if let Some(pass) = &mut self.voxel_debug {
            pass.update(self.settings.time_s, slot);
        }
        let offset = (slot as u64 * self.frame_stride) as usize;
        let bytes = bytemuck::bytes_of(&self.frame_data);
        if let Some(m) = self.frame.mapped_mut() {
            m[offset..offset + bytes.len()].copy_from_slice(bytes);
        }
    }

    /// Frames the indirect light has accumulated since the last reset (`None`: GI off).
    pub fn gi_accumulated_frames(&self) -> Option<u32> {
        self.gi.as_ref().map(|(gi, _)| gi.accumulated_frames())
    }

    /// Number of culled camera draws and total draws (for statistics and tests).
    pub fn camera_draws(&self) -> (usize, usize) {
        let visible = self.draws.read().map(|d| d.camera.len()).unwrap_or(0);
        (visible, self.all_draws.len())
    }

    pub fn shadow_view_count(&self) -> u32 {
        self.shadow_view_count
    }

    pub fn has_phong(&self) -> bool {
        self.has_phong
    }

    /// Declares the frame with read-back of the radiance and the tone-mapped image (at the
    /// size given to [`Renderer::new`]).
    pub fn graph(&self) -> RenderGraph {
        let mut g = RenderGraph::new();
        let FrameImages { radiance, ldr } = self.declare(&mut g);
        let (w, h) = (self.settings.width, self.settings.height);
        let hdr_buf = g.import_buffer(&self.readback_hdr, Access::HostRead);
        let ldr_buf = g.import_buffer(&self.readback_ldr, Access::HostRead);
        let extent = vk::Extent3D {
            width: w,
            height: h,
            depth: 1,
        };
        g.add_pass("readback_hdr")
            .read(radiance, Access::TransferRead)
            .write(hdr_buf, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd.copy_image_to_buffer(
                    ctx.image(radiance).raw,
                    extent,
                    0,
                    1,
                    ctx.buffer(hdr_buf).raw,
                )
            });
        g.add_pass("readback_ldr")
            .read(ldr, Access::TransferRead)
            .write(ldr_buf, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd.copy_image_to_buffer(
                    ctx.image(ldr).raw,
                    extent,
                    0,
                    1,
                    ctx.buffer(ldr_buf).raw,
                )
            });
        g
    }

    /// Declares the frame's passes into `g` at `settings`' size and returns the images it
    /// produces, for callers that add their own outputs (the viewer presents `ldr`). Nothing
    /// is an output yet: passes that feed nothing the caller adds are culled.
    pub fn declare(&self, g: &mut RenderGraph) -> FrameImages {
        let s = &self.settings;
        let (w, h) = (s.width, s.height);
        let frame = g.import_buffer(&self.frame, Access::StorageRead(Shader::Compute));
        let frame_raw = self.frame.raw;
        let stride = self.frame_stride;
        let frame_size = std::mem::size_of::<GpuFrame>() as u64;
        let frame_desc = move |slot: usize| Descriptor::StorageBuffer {
            binding: 0,
            buffer: frame_raw,
            offset: slot as u64 * stride,
            range: frame_size,
        };
        let (vb, ib, mb) = (self.vertices.raw, self.indices.raw, self.materials.raw);
        let voxel_image = self.voxels.as_ref().map(|v| v.add_passes(g));

        // Shadow maps: one layer per shadow view (a 1x1 cleared layer when there are none, so
        // the shading pass always has a map to bind).
        let views = self.shadow_view_count;
        let res = if views == 0 { 1 } else { s.shadow.resolution };
        let shadow_map = g.create_image(
            ImageDesc::new_2d("shadow maps", DEPTH, res, res).with_layers(views.max(1)),
        );
        let pipe = self.pipelines.shadow;
        let draws = self.draws.clone();
        g.add_pass("shadow_depth")
            .read(frame, Access::StorageRead(Shader::Geometry))
            .write(shadow_map, Access::DepthAttachment)
            .record(move |ctx| {
                let map = ctx.image(shadow_map);
                let depth = Attachment {
                    view: map.view,
                    clear: Some(vk::ClearValue {
                        depth_stencil: vk::ClearDepthStencilValue {
                            depth: 1.0,
                            stencil: 0,
                        },
                    }),
                };
                ctx.cmd
                    .begin_rendering_layers(map.extent_2d(), views.max(1), &[], Some(depth));
                ctx.cmd.bind(
                    &pipe,
                    &[frame_desc(ctx.slot), Descriptor::storage_buffer(1, mb)],
                );
                ctx.cmd.bind_vertex_buffer(vb);
                ctx.cmd.bind_index_buffer(ib);
                draw_shadow_views(ctx.cmd, &pipe, &draws, |d, v| GpuShadowPush {
                    model: d.model.to_cols_array(),
                    view: v,
                    material: d.material,
                    _pad: [0; 2],
                });
                ctx.cmd.end_rendering();
            });

        // G-buffer.
        let albedo = g.create_image(ImageDesc::new_2d("gbuffer albedo", GBUFFER_COLOR, w, h));
        let normal = g.create_image(ImageDesc::new_2d("gbuffer normal", GBUFFER_COLOR, w, h));
        let specular = self
            .has_phong
            .then(|| g.create_image(ImageDesc::new_2d("gbuffer specular", GBUFFER_COLOR, w, h)));
        let depth = g.create_image(ImageDesc::new_2d("gbuffer depth", DEPTH, w, h));
        let pipe = self.pipelines.gbuffer;
        let draws = self.draws.clone();
        let tex_handles: Vec<_> = self
            .textures
            .iter()
            .map(|t| g.import_image(t, Access::Sampled(Shader::Fragment)))
            .collect();
        let tex_sampler = self.texture_sampler;
        let mut pass = g
            .add_pass("gbuffer")
            .read(frame, Access::StorageRead(Shader::Graphics))
            .write(albedo, Access::ColorAttachment)
            .write(normal, Access::ColorAttachment)
            .write(depth, Access::DepthAttachment);
        if let Some(spec) = specular {
            pass = pass.write(spec, Access::ColorAttachment);
        }
        for &t in &tex_handles {
            pass = pass.read(t, Access::Sampled(Shader::Fragment));
        }
        let placeholder = tex_handles[tex_handles.len() - 1];
        pass.record(move |ctx| {
            let clear = Some(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            });
            let mut colors = vec![
                Attachment {
                    view: ctx.image(albedo).view,
                    clear,
                },
                Attachment {
                    view: ctx.image(normal).view,
                    clear,
                },
            ];
            if let Some(spec) = specular {
                colors.push(Attachment {
                    view: ctx.image(spec).view,
                    clear,
                });
            }
            let depth_att = Attachment {
                view: ctx.image(depth).view,
                clear: Some(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: 1.0,
                        stencil: 0,
                    },
                }),
            };
            ctx.cmd
                .begin_rendering(ctx.image(albedo).extent_2d(), &colors, Some(depth_att));
            let texture = |binding: u32, t: Option<usize>| Descriptor::SampledImage {
                binding,
                view: ctx
                    .image(
                        t.and_then(|i| tex_handles.get(i).copied())
                            .unwrap_or(placeholder),
                    )
                    .view,
                sampler: tex_sampler,
            };
            ctx.cmd.bind(
                &pipe,
                &[
                    frame_desc(ctx.slot),
                    Descriptor::storage_buffer(1, mb),
                    texture(2, None),
                    texture(3, None),
                ],
            );
            ctx.cmd.bind_vertex_buffer(vb);
            ctx.cmd.bind_index_buffer(ib);
            if let Ok(lists) = draws.read() {
                let mut bound = (None, None);
                for d in &lists.camera {
                    if (d.texture, d.bump) != bound {
                        ctx.cmd
                            .push_descriptors(&pipe, &[texture(2, d.texture), texture(3, d.bump)]);
                        bound = (d.texture, d.bump);
                    }
                    let push = GpuGbufferPush {
                        model: d.model.to_cols_array(),
                        material: d.material,
                        _pad: [0; 3],
                    };
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd
                        .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                }
            }
            ctx.cmd.end_rendering();
        });

        // Deferred direct light.
        let radiance = g.create_image(ImageDesc::new_2d("radiance", HDR, w, h));
        let pipe = self.pipelines.deferred;
        let sampler = self.sampler;
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let mut pass = g
            .add_pass("deferred_direct")
            .read(frame, Access::StorageRead(Shader::Compute))
            .read(albedo, Access::Sampled(Shader::Compute))
            .read(normal, Access::Sampled(Shader::Compute))
            .read(depth, Access::Sampled(Shader::Compute))
            .read(shadow_map, Access::Sampled(Shader::Compute))
            .write(radiance, Access::StorageWrite(Shader::Compute));
        if let Some(spec) = specular {
            pass = pass.read(spec, Access::Sampled(Shader::Compute));
        }
        pass.record(move |ctx| {
            let sampled = |binding, view| Descriptor::SampledImage {
                binding,
                view,
                sampler,
            };
            // Without Phong materials the specular binding is never read; bind albedo there.
            let spec_view = specular
                .map(|s| ctx.image(s).view)
                .unwrap_or(ctx.image(albedo).view);
            ctx.cmd.bind(
                &pipe,
                &[
                    frame_desc(ctx.slot),
                    sampled(1, ctx.image(albedo).view),
                    sampled(2, ctx.image(normal).view),
                    sampled(3, spec_view),
                    sampled(4, ctx.image(depth).view),
                    sampled(5, ctx.image(shadow_map).view),
                    Descriptor::StorageImage {
                        binding: 6,
                        view: ctx.image(radiance).view,
                    },
                ],
            );
            ctx.cmd.dispatch(groups.0, groups.1, 1);
        });

        // Indirect light: reflective light maps over the shadow views, then the GI passes.
        let radiance = match (&self.gi, voxel_image) {
            (Some((gi, light_map_pipe)), Some(voxels)) => {
                let res = gi.settings.light_map_resolution.max(1);
                let layers = views.max(1);
                let mut rlm = |name: &str, format| {
                    g.create_image(ImageDesc::new_2d(name, format, res, res).with_layers(layers))
                };
                let rlm_radiance = rlm("light map radiance", LIGHT_MAP_RADIANCE);
                let rlm_position = rlm("light map position", vk::Format::R32G32B32A32_SFLOAT);
                let rlm_normal = rlm("light map normal", vk::Format::R16G16B16A16_SFLOAT);
                let rlm_depth = rlm("light map depth", DEPTH);
                let pipe = *light_map_pipe;
                let draws = self.draws.clone();
                g.add_pass("light_map")
                    .read(frame, Access::StorageRead(Shader::Graphics))
                    .write(rlm_radiance, Access::ColorAttachment)
                    .write(rlm_position, Access::ColorAttachment)
                    .write(rlm_normal, Access::ColorAttachment)
                    .write(rlm_depth, Access::DepthAttachment)
                    .record(move |ctx| {
                        let clear = Some(vk::ClearValue {
                            color: vk::ClearColorValue { float32: [0.0; 4] },
                        });
                        let colors = [rlm_radiance, rlm_position, rlm_normal].map(|h| Attachment {
                            view: ctx.image(h).view,
                            clear,
                        });
                        let depth = Attachment {
                            view: ctx.image(rlm_depth).view,
                            clear: Some(vk::ClearValue {
                                depth_stencil: vk::ClearDepthStencilValue {
                                    depth: 1.0,
                                    stencil: 0,
                                },
                            }),
                        };
                        ctx.cmd.begin_rendering_layers(
                            ctx.image(rlm_depth).extent_2d(),
                            layers,
                            &colors,
                            Some(depth),
                        );
                        ctx.cmd.bind(
                            &pipe,
                            &[frame_desc(ctx.slot), Descriptor::storage_buffer(1, mb)],
                        );
                        ctx.cmd.bind_vertex_buffer(vb);
                        ctx.cmd.bind_index_buffer(ib);
                        draw_shadow_views(ctx.cmd, &pipe, &draws, |d, v| GpuLightMapPush {
                            model: d.model.to_cols_array(),
                            view: v,
                            material: d.material,
                            _pad: [0; 2],
                        });
                        ctx.cmd.end_rendering();
                    });
                gi.add_passes(
                    g,
                    &crate::gi::GiInputs {
                        frame,
                        frame_descriptor: frame_desc(0),
                        frame_stride: stride,
                        albedo,
                        normal,
                        depth,
                        direct: radiance,
                        voxels,
                        rlm_radiance,
                        rlm_position,
                        rlm_normal,
                        shadow_map,
                        specular,
                        materials: mb,
                        width: w,
                        height: h,
                    },
                    self.voxels.as_ref(),
                )
            }
            _ => radiance,
        };

        // Tone mapping.
        let ldr = g.create_image(ImageDesc::new_2d("ldr", vk::Format::R8G8B8A8_UNORM, w, h));
        let pipe = self.pipelines.tonemap;
        let tm = s.tonemap;
        g.add_pass("tonemap")
            .read(radiance, Access::Sampled(Shader::Compute))
            .write(ldr, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                ctx.cmd.bind(
                    &pipe,
                    &[
                        Descriptor::SampledImage {
                            binding: 0,
                            view: ctx.image(radiance).view,
                            sampler,
                        },
                        Descriptor::StorageImage {
                            binding: 1,
                            view: ctx.image(ldr).view,
                        },
                    ],
                );
                let push = GpuTonemapPush {
                    exposure: tm.exposure,
                    op: tm.operator.shader_id(),
                    white: tm.white,
                    drago_bias: tm.drago_bias,
                };
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });

        // A debug view replaces the lit image: the read-backs take its images, and the graph
        // culls deferred light, tone mapping, G-buffer and shadows, which nothing reads then.
        let (radiance, ldr) = match (&self.voxel_debug, &self.voxels, voxel_image) {
            _ if self.atlas_view.is_some() => {
                let value = g.create_image(ImageDesc::new_2d("atlas debug value", HDR, w, h));
                let color = g.create_image(ImageDesc::new_2d(
                    "atlas debug color",
                    vk::Format::R8G8B8A8_UNORM,
                    w,
                    h,
                ));
                if let Some(pass) = &self.atlas_view {
                    pass.add_passes(g, value, color, (w, h));
                }
                (value, color)
            }
            (Some(pass), Some(v), Some(image)) => {
                let value = g.create_image(ImageDesc::new_2d("voxel debug value", HDR, w, h));
                let color = g.create_image(ImageDesc::new_2d(
                    "voxel debug color",
                    vk::Format::R8G8B8A8_UNORM,
                    w,
                    h,
                ));
                pass.add_pass(g, v, image, value, color, (w, h));
                (value, color)
            }
            _ => (radiance, ldr),
        };

        FrameImages { radiance, ldr }
    }

    /// Linear radiance of the last completed frame.
    pub fn hdr_image(&self) -> HdrImage {
        let (w, h) = (self.settings.width, self.settings.height);
        let data: Vec<[f32; 3]> = self
            .readback_hdr
            .mapped()
            .map(|m| {
                bytemuck::cast_slice::<u8, [f32; 4]>(&m[..(w * h * 16) as usize])
                    .iter()
                    .map(|p| [p[0], p[1], p[2]])
                    .collect()
            })
            .unwrap_or_else(|| vec![[0.0; 3]; (w * h) as usize]);
        HdrImage {
            width: w,
            height: h,
            data,
        }
    }

    /// Tone-mapped sRGB RGBA8 pixels of the last completed frame.
    pub fn ldr_pixels(&self) -> Vec<u8> {
        let n = (self.settings.width * self.settings.height * 4) as usize;
        self.readback_ldr
            .mapped()
            .map(|m| m[..n].to_vec())
            .unwrap_or_default()
    }

    /// GPU times of the one-time passes the renderer submitted outside its frame graph
    /// (atlas building, static voxelization), in order.
    pub fn setup_timings(&self) -> Vec<PassTiming> {
        self.voxels
            .as_ref()
            .map(|v| v.setup_timings().to_vec())
            .unwrap_or_default()
    }

    /// What the debug view shows and measured in `value` (its value image), for the CLI.
    pub fn debug_description(&self, value: &HdrImage) -> Option<String> {
        match (&self.atlas_view, &self.settings.debug) {
            (Some(pass), _) => Some(pass.describe(value)),
            (None, Some(d)) => Some(crate::voxel::debug_view::describe(d, value)),
            _ => None,
        }
    }

    pub fn destroy(self, ctx: &Context) {
        if let Some(pass) = self.voxel_debug {
            pass.destroy(ctx);
        }
        if let Some(pass) = self.atlas_view {
            pass.destroy(ctx);
        }
        if let Some(v) = self.voxels {
            v.destroy(ctx);
        }
        if let Some((gi, light_map)) = self.gi {
            gi.destroy(ctx);
            ctx.destroy_graphics_pipeline(light_map);
        }
        ctx.destroy_graphics_pipeline(self.pipelines.gbuffer);
        ctx.destroy_graphics_pipeline(self.pipelines.shadow);
        ctx.destroy_compute_pipeline(self.pipelines.deferred);
        ctx.destroy_compute_pipeline(self.pipelines.tonemap);
        ctx.destroy_sampler(self.sampler);
        ctx.destroy_sampler(self.texture_sampler);
        for t in self.textures {
            ctx.destroy_image(t);
        }
        for b in [
            self.vertices,
            self.indices,
            self.materials,
            self.frame,
            self.readback_hdr,
            self.readback_ldr,
        ] {
            ctx.destroy_buffer(b);
        }
    }
}

fn gpu_light(light: &Light, first_view: u32, views: u32) -> GpuLight {
    let v4 = |v: Vec3| [v.x, v.y, v.z, 0.0];
    match *light {
        Light::Point {
            position,
            intensity_w_sr,
        } => GpuLight {
            position: v4(position),
            intensity: v4(intensity_w_sr),
            info: [LIGHT_POINT, first_view, views, 0],
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => GpuLight {
            position: v4(position),
            direction: v4(direction),
            intensity: v4(intensity_w_sr),
            spot: [
                cutoff_deg.to_radians().cos(),
                cutoff_deg.to_radians(),
                beam_deg.to_radians(),
                0.0,
            ],
            info: [LIGHT_SPOT, first_view, views, 0],
        },
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => GpuLight {
            direction: v4(direction),
            intensity: v4(irradiance_w_m2),
            info: [LIGHT_DIRECTIONAL, first_view, views, 0],
            ..Default::default()
        },
    }
}

/// Uploads every mesh into one vertex and one index buffer; returns one draw per submesh of
/// The scene's meshes on the GPU: one vertex and one index buffer, a draw per submesh of each
/// object, and each mesh's offsets in the buffers.
struct Geometry {
    vertices: Buffer,
    indices: Buffer,
    draws: Vec<Draw>,
    mesh_base: Vec<(i32, u32)>,
}

/// each object at time `t_s`.
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
            let texture = scene.materials.get(material).and_then(|m| m.albedo_texture);
            let bump = scene.materials.get(material).and_then(|m| m.bump_texture);
            draws.push(Draw {
                first_index: ibase + sub.first_index,
                index_count: sub.index_count,
                vertex_offset: vbase,
                material: material as u32,
                texture,
                bump,
                object: object_index,
                submesh: si,
                local_aabb: mesh.aabb,
                model,
                aabb,
            });
        }
    }
    let vb = ctx.upload_buffer(
        "vertices",
        bytemuck::cast_slice(&vertices),
        vk::BufferUsageFlags::VERTEX_BUFFER,
    )?;
    let ib = ctx.upload_buffer(
        "indices",
        bytemuck::cast_slice(&indices),
        vk::BufferUsageFlags::INDEX_BUFFER,
    )?;
    Ok(Geometry {
        vertices: vb,
        indices: ib,
        draws,
        mesh_base,
    })
}

/// Draws every shadow view's draw list with `pipe` (bound with its buffers), the push
/// constants of draw `d` in view `v` from `push(d, v)`: the shadow-depth and light-map passes.
fn draw_shadow_views<P: bytemuck::Pod>(
    cmd: &Cmd,
    pipe: &GraphicsPipeline,
    draws: &RwLock<DrawLists>,
    push: impl Fn(&Draw, u32) -> P,
) {
    let Ok(lists) = draws.read() else {
        return;
    };
    for (v, list) in lists.shadow.iter().enumerate() {
        for d in list {
            cmd.push_constants(pipe, bytemuck::bytes_of(&push(d, v as u32)));
            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
        }
    }
}

/// The reflective light-map pipeline (`light_map.{vert,geom,frag}`); `has_dissolve`: some
/// material has MTL d < 1, whose coverage the light map shares with the shadow maps.
fn create_light_map_pipeline(
    ctx: &Context,
    has_dissolve: bool,
) -> Result<GraphicsPipeline, VkError> {
    ctx.graphics_pipeline(&GraphicsPipelineDesc {
        vertex: "light_map.vert".into(),
        geometry: Some("light_map.geom".into()),
        fragment: "light_map.frag".into(),
        push: crate::vk::PushLayout::of::<GpuLightMapPush>(),
        vertex_stride: std::mem::size_of::<GpuVertex>() as u32,
        vertex_attributes: vec![
            (vk::Format::R32G32B32_SFLOAT, 0),
            (vk::Format::R32G32B32_SFLOAT, 12),
        ],
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        cull_mode: vk::CullModeFlags::NONE,
        color_formats: vec![
            LIGHT_MAP_RADIANCE,
            vk::Format::R32G32B32A32_SFLOAT,
            vk::Format::R16G16B16A16_SFLOAT,
        ],
        depth_format: Some(DEPTH),
        depth_test: true,
        depth_write: true,
        depth_bias: false,
        logic_op: None,
        spec: vec![(0, u32::from(has_dissolve))],
    })
}

/// A 1x1 white texture bound where a draw has no albedo map.
fn placeholder_texture() -> crate::scene::TextureData {
    crate::scene::TextureData {
        path: "placeholder".into(),
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
        srgb: true,
    }
}

fn create_pipelines(
    ctx: &Context,
    has_phong: bool,
    has_textures: bool,
    has_bump: bool,
    has_dissolve: bool,
    paraboloid_shadows: bool,
) -> Result<Pipelines, VkError> {
    let vertex_attributes = vec![
        (vk::Format::R32G32B32_SFLOAT, 0),
        (vk::Format::R32G32B32_SFLOAT, 12),
        (vk::Format::R32G32_SFLOAT, 24),
    ];
    let mut colors = vec![GBUFFER_COLOR, GBUFFER_COLOR];
    if has_phong {
        colors.push(GBUFFER_COLOR);
    }
    let gbuffer = ctx.graphics_pipeline(&GraphicsPipelineDesc {
        vertex: "gbuffer.vert".into(),
        geometry: None,
        fragment: "gbuffer.frag".into(),
        push: crate::vk::PushLayout::of::<GpuGbufferPush>(),
        vertex_stride: std::mem::size_of::<GpuVertex>() as u32,
        vertex_attributes: vertex_attributes.clone(),
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        cull_mode: vk::CullModeFlags::NONE,
        color_formats: colors,
        depth_format: Some(DEPTH),
        depth_test: true,
        depth_write: true,
        depth_bias: false,
        logic_op: None,
        spec: vec![
            (0, u32::from(has_phong)),
            (1, u32::from(has_textures)),
            (2, u32::from(has_bump)),
            (3, u32::from(has_dissolve)),
        ],
    })?;
    let shadow = ctx.graphics_pipeline(&GraphicsPipelineDesc {
        vertex: "shadow_depth.vert".into(),
        geometry: Some("shadow_depth.geom".into()),
        fragment: if paraboloid_shadows {
            "shadow_depth_paraboloid.frag".into()
        } else {
            "shadow_depth.frag".into()
        },
        push: crate::vk::PushLayout::of::<GpuShadowPush>(),
        vertex_stride: std::mem::size_of::<GpuVertex>() as u32,
        vertex_attributes: vec![(vk::Format::R32G32B32_SFLOAT, 0)],
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        cull_mode: vk::CullModeFlags::NONE,
        color_formats: vec![],
        depth_format: Some(DEPTH),
        depth_test: true,
        depth_write: true,
        depth_bias: false,
        logic_op: None,
        spec: vec![(0, u32::from(has_dissolve))],
    })?;
    let deferred =
        ctx.compute_pipeline("deferred_direct.comp", None, &[(0, u32::from(has_phong))])?;
    let tonemap = ctx.compute_pipeline(
        "tonemap.comp",
        crate::vk::PushLayout::of::<GpuTonemapPush>(),
        &[],
    )?;
    Ok(Pipelines {
        gbuffer,
        shadow,
        deferred,
        tonemap,
    })
}

/// The result of [`render_image`].
pub struct RenderOutput {
    pub hdr: HdrImage,
    /// Tone-mapped sRGB RGBA8.
    pub ldr: Vec<u8>,
    pub timings: Vec<PassTiming>,
    /// Compiled-graph facts: live passes, culled passes, transient bytes aliased / not.
    pub live_passes: Vec<String>,
    pub transient_bytes: (u64, u64),
    /// A debug view's description ([`Renderer::debug_description`]).
    pub debug_description: Option<String>,
}

/// Renders one frame of `scene` headless.
pub fn render_image(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderOutput, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    // The path tracer converges over frames; everything else is done in one.
    let frames = match settings.gi.method {
        crate::gi::GiMethod::Pathtrace => settings.gi.accumulate_frames.max(1) as usize,
        _ => 1,
    };
    let result = run_frames(ctx, &mut renderer, frames);
    let out = result.map(|timings| {
        let hdr = renderer.hdr_image();
        let ldr = renderer.ldr_pixels();
        let description = renderer.debug_description(&hdr);
        (hdr, ldr, (timings, description))
    });
    let (exec_facts, out) = match out {
        Ok((hdr, ldr, ((timings, live, bytes), description))) => {
            (Some((live, bytes)), Ok((hdr, ldr, timings, description)))
        }
        Err(e) => (None, Err(e)),
    };
    renderer.destroy(ctx);
    let (hdr, ldr, timings, debug_description) = out?;
    let (live_passes, transient_bytes) = exec_facts.unwrap_or_default();
    Ok(RenderOutput {
        hdr,
        ldr,
        timings,
        live_passes,
        transient_bytes,
        debug_description,
    })
}

type FrameFacts = (Vec<PassTiming>, Vec<String>, (u64, u64));

/// Runs `frames` frames; returns the last frame's timings and graph facts.
fn run_frames(
    ctx: &Context,
    renderer: &mut Renderer,
    frames: usize,
) -> Result<FrameFacts, RenderError> {
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let result = (|| -> Result<FrameFacts, RenderError> {
        let mut frame_loop = FrameLoop::new(
            ctx,
            MAX_FRAMES_IN_FLIGHT,
            exec.compiled().order.len() as u32,
        )?;
        let mut last = Vec::new();
        let run = (|| -> Result<(), RenderError> {
            for _ in 0..frames {
                let slot = frame_loop.current_slot();
                // begin() waits for the slot's fence before the frame constants are rewritten.
                let (slot_b, cmd, ts, done) = frame_loop.begin(ctx)?;
                debug_assert_eq!(slot, slot_b);
                if !done.is_empty() {
                    last = done;
                }
                renderer.write_frame(slot);
                exec.record(&cmd, slot, ts);
                frame_loop.submit(ctx, &[], &[])?;
            }
            Ok(())
        })();
        let finished = frame_loop.finish(ctx);
        frame_loop.destroy(ctx);
        run?;
        if let Some(t) = finished?.into_iter().last() {
            last = t;
        }
        let c = exec.compiled();
        let live = c.order.iter().map(|&p| c.pass_names[p].clone()).collect();
        Ok((
            last,
            live,
            (c.memory.peak_aliased_bytes, c.memory.unaliased_bytes),
        ))
    })();
    let _ = ctx.wait_idle();
    exec.destroy(ctx);
    result
}

/// What [`profile_scene`] measured.
pub struct ProfileRun {
    /// Per measured frame, the timings of each pass in order.
    pub frames: Vec<Vec<PassTiming>>,
    pub live_passes: Vec<String>,
    pub culled_passes: Vec<String>,
    /// Transient memory with and without aliasing.
    pub transient_memory: crate::graph::MemoryStats,
    /// One-time passes submitted before the first frame, outside the frame graph.
    pub setup: Vec<PassTiming>,
}

/// Per-pass GPU timing over many frames of a scene (for `voxgi profile`).
pub fn profile_scene(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    frames: usize,
    warmup: usize,
) -> Result<ProfileRun, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    let result = (|| {
        let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
        let r = (|| -> Result<Vec<Vec<PassTiming>>, RenderError> {
            let mut frame_loop = FrameLoop::new(
                ctx,
                MAX_FRAMES_IN_FLIGHT,
                exec.compiled().order.len() as u32,
            )?;
            let mut measured = Vec::new();
            let run = (|| -> Result<(), RenderError> {
                for i in 0..warmup + frames {
                    let slot = frame_loop.current_slot();
                    let (_, cmd, ts, done) = frame_loop.begin(ctx)?;
                    if i >= warmup + MAX_FRAMES_IN_FLIGHT && !done.is_empty() {
                        measured.push(done);
                    }
                    renderer.write_frame(slot);
                    exec.record(&cmd, slot, ts);
                    frame_loop.submit(ctx, &[], &[])?;
                }
                Ok(())
            })();
            let finished = frame_loop.finish(ctx);
            frame_loop.destroy(ctx);
            run?;
            measured.extend(finished?.into_iter().filter(|t| !t.is_empty()));
            Ok(measured)
        })();
        let _ = ctx.wait_idle();
        let c = exec.compiled();
        let live = c.order.iter().map(|&p| c.pass_names[p].clone()).collect();
        let culled = c.culled.iter().map(|&p| c.pass_names[p].clone()).collect();
        let memory = c.memory;
        exec.destroy(ctx);
        r.map(|frames| ProfileRun {
            frames,
            live_passes: live,
            culled_passes: culled,
            transient_memory: memory,
            setup: renderer.setup_timings(),
        })
    })();
    renderer.destroy(ctx);
    result
}

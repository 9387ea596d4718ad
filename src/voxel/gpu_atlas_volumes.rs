//! Non-binary atlas voxelization (Thiedemann 2010, §4.3.2): the atlas
//! points that set the bits ([`super::gpu_atlas`]) also write albedo and normal volumes
//! congruent with them, for the GI methods that read more than occupancy (the voxel path
//! tracer and the direct-radiance volume). They exist only when such a method runs
//! ([`super::frame::VoxelFrame::enable_attribute_volumes`]).
//!
//! # Passes (named after their GLSL stems)
//! - `voxelize_atlas_volumes` (graphics): the point lists drawn as `POINT_LIST`, one vertex
//!   per point pulled from its buffer; the vertex shader finds the point's voxel with the
//!   same f32 operations as `voxelize_atlas.comp` (`atlas_voxel.glsl`), places it at its
//!   column in a viewport of the grid's x,y resolution, and the geometry shader sets
//!   `gl_Layer` = its depth index. Targets: two `RGBA16F` 2D arrays with one layer per depth
//!   index, blended additively: (albedo, 1) and the unit normal per point.
//! - `voxelize_atlas_resolve` (compute): static sums + this frame's sums → the `RGBA8` albedo
//!   and `RGBA8_SNORM` normal 3D volumes the path tracer samples; alpha = 1 exactly where a
//!   point landed.
//! - With albedo textures (`map_Kd`, [`super::maps::MapUse::albedo`]) each point's albedo is
//!   the texture sampled at the point instead of `Kd`, so the sums' mean is the texture's
//!   area-weighted mean over the voxel's surface.
//! - With value volumes ([`ValueVolumes`]: emitters, the path tracer's material volume) the
//!   splat also sums (radiance, 1) of emitters' points and the material texels of Phong and
//!   GGX points (the normal sums' w counting them) into one more target each, the PBR maps
//!   sampled at each point ([`super::maps`]); `voxelize_atlas_emission` resolves the mean
//!   radiance of the emitters' points (emitters own the voxels they share, as in the triangle
//!   voxelizer), `voxelize_atlas_material` the mean texel of the lobe points where they are at
//!   least half of the voxel's points (else Lambert). The triangle voxelizer takes the owner
//!   triangle's value instead; both agree wherever one surface and one map value fill a voxel.
//!
//! # Why averaging, not the thesis's last writer
//! The thesis keeps the last point drawn into a voxel (§4.3.2), which depends on the order of
//! the point list (built by atomics, so arbitrary) and shows back-face normals on thin parts
//! (the elephant's ear). Every atlas texel stands for the same area in meters, so summing
//! (albedo, 1) and dividing gives the area-weighted mean albedo, independent of the order;
//! summed normals give the mean orientation (a voxel on an edge gets the bisector).
//!
//! # Static and dynamic objects (thesis §4.3.3)
//! Like the bits: the static objects' sums are splatted once into persistent layers, each
//! frame that re-voxelizes splats only the dynamic objects into transient layers, and the
//! resolve adds both. Nothing records while nothing moves (the voxel frame's [`SlotGate`]).

use super::attributes::{material_texel, AttributeHandles, ValueVolumes};
pub use super::attributes::{AttributeVolumes, ALBEDO_FORMAT, NORMAL_FORMAT, VOLUME_STATE};
use super::gpu::{GpuVoxelError, SlotGate};
use super::gpu_atlas::{import_chunks, AtlasScene, FrameAt, GpuAtlasVoxelizePush, ModelAt};
use super::maps::{GpuTriangleMaps, VoxelMaps};
use super::VoxelGrid;
use crate::graph::run_once;
use crate::graph::{Access, BufferHandle, ImageHandle, Load, RenderGraph, Shader};
use crate::scene::{PreExposure, Scene};
use crate::vk::{
    vk, Buffer, ComputePipeline, Context, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    PipelineHandle, VkError,
};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Format of the per-voxel sums: f16 counts are exact up to 2048 points per voxel, far more
/// than an atlas sized for the grid puts into one (a few per surface crossing it).
pub const SUM_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// Push constants of `voxelize_atlas_resolve.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAtlasResolvePush {
    /// `res_x, res_y, D`, and bit 0: static sums bound, bit 1: frame sums bound.
    pub dims: [u32; 4],
}

crate::push_constants!(GpuAtlasResolvePush { dims });

/// Pipelines, per-instance triangle attributes and the static objects' sums.
pub struct AtlasVolumes {
    splat: GraphicsPipeline,
    resolve: ComputePipeline,
    /// With an emission volume: `voxelize_atlas_emission`.
    emission_resolve: Option<ComputePipeline>,
    /// With a material volume: `voxelize_atlas_material`.
    material_resolve: Option<ComputePipeline>,
    sampler: crate::vk::Sampler,
    /// Per instance (static instances first, then dynamic, as in [`AtlasScene`]) and per
    /// sequence frame (one for rigid objects): the frame's triangles in model space with
    /// the object's material albedo in the vertices' w (the layout of
    /// `voxelize_attributes.comp`), indexed by the points' triangle index. Per frame because
    /// a deforming frame turns its faces (the normals follow).
    triangles: Vec<Vec<Buffer>>,
    /// With value volumes, laid out like `triangles`: per triangle its emission, material
    /// texel and [`GpuTriangleMaps`] ([`model_values`]).
    values: Vec<Vec<Buffer>>,
    /// The value volumes the splat sums and the maps it samples.
    value_volumes: ValueVolumes,
    /// The PBR maps the splat samples per texel, if any.
    maps: Option<VoxelMaps>,
    /// The static instances' sums, splatted once; absent when the statics are splatted every
    /// frame (`revoxelize_static`) or there are none.
    static_sums: Option<SumImages>,
    /// Without a slot gate (nothing ever moves) the volumes are resolved by the first frame:
    /// open in the slot of the first [`Self::prepare`], closed after.
    resolve_once: Arc<SlotGate>,
    /// [`Self::prepare`] has opened a first frame.
    resolved: bool,
}

/// The persistent sum layers of the static instances (value sums only with their volume).
struct SumImages {
    albedo: Image,
    normal: Image,
    emission: Option<Image>,
    material: Option<Image>,
}

/// Sum layers in one graph: the splat's color targets, in attachment order.
#[derive(Clone, Copy)]
struct Sums {
    albedo: ImageHandle,
    normal: ImageHandle,
    emission: Option<ImageHandle>,
    material: Option<ImageHandle>,
}

/// One sequence frame of a [`Splat`]: its point chunks `(points, count)`, triangles, values
/// and coverage (none for an opaque object).
type SplatFrame = (
    Vec<(BufferHandle, u32)>,
    BufferHandle,
    BufferHandle,
    Option<BufferHandle>,
);

/// Binding of the per-triangle coverage in `voxelize_atlas_volumes.vert`
/// (`ATLAS_COVERAGE_BINDING`).
const COVERAGE_BINDING: u32 = 5;

/// A draw of one instance: per sequence frame its point chunks `(points, count)`, its
/// triangles and its values (the triangles without value volumes), and which frame and model
/// matrix a slot uses.
struct Splat {
    frames: Vec<SplatFrame>,
    frame: FrameAt,
    model: ModelAt,
}

impl AtlasVolumes {
    /// Builds the pipelines and triangle attributes of `atlas`'s instances and, when
    /// `statics_once`, splats the static instances once; `values`: also the emission and
    /// material sums and their maps.
    pub fn new(
        ctx: &Context,
        atlas: &AtlasScene,
        scene: &Scene,
        grid: &VoxelGrid,
        statics_once: bool,
        values: ValueVolumes,
    ) -> Result<Self, GpuVoxelError> {
        let mut desc = GraphicsPipelineDesc::fullscreen(
            "voxelize_atlas_volumes.vert",
            "voxelize_atlas_volumes.frag",
            SUM_FORMAT,
        );
        desc.geometry = Some("voxelize_atlas_volumes.geom".into());
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        let targets = 2 + usize::from(values.emission) + usize::from(values.material);
        desc.color_formats = vec![SUM_FORMAT; targets];
        desc.push = crate::vk::PushLayout::of::<GpuAtlasVoxelizePush>();
        desc.spec = crate::spec_constants![
            HAS_EMISSION = values.emission,
            HAS_MATERIAL = values.material,
            HAS_MAPS = values.maps.any(),
        ]
        .to_vec();
        let splat = ctx.graphics_pipeline_additive(&desc)?;
        let push = crate::vk::PushLayout::of::<GpuAtlasResolvePush>;
        let resolve = ctx.compute_pipeline("voxelize_atlas_resolve.comp", push(), &[])?;
        let emission_resolve = values
            .emission
            .then(|| ctx.compute_pipeline("voxelize_atlas_emission.comp", push(), &[]))
            .transpose()?;
        let material_resolve = values
            .material
            .then(|| ctx.compute_pipeline("voxelize_atlas_material.comp", push(), &[]))
            .transpose()?;
        let mut me = Self {
            splat,
            resolve,
            emission_resolve,
            material_resolve,
            sampler: ctx.create_sampler(vk::Filter::NEAREST, false)?,
            triangles: Vec::new(),
            values: Vec::new(),
            value_volumes: values,
            maps: VoxelMaps::new(ctx, scene, values.maps)?,
            static_sums: None,
            resolve_once: Arc::new(SlotGate::default()),
            resolved: false,
        };
        me.init(ctx, atlas, scene, grid, statics_once)?;
        Ok(me)
    }

    /// Whether the splat sums the emission volume's values.
    pub fn has_emission(&self) -> bool {
        self.value_volumes.emission
    }

    /// Whether the splat sums the material volume's values.
    pub fn has_material(&self) -> bool {
        self.value_volumes.material
    }

    fn init(
        &mut self,
        ctx: &Context,
        atlas: &AtlasScene,
        scene: &Scene,
        grid: &VoxelGrid,
        statics_once: bool,
    ) -> Result<(), GpuVoxelError> {
        let objects = atlas
            .static_instances
            .iter()
            .map(|&(_, _, o)| (o, scene.objects.get(o).map(|o| vec![o.mesh])))
            .chain(atlas.dynamic_instances.iter().map(|d| {
                (
                    d.object_index,
                    Some(d.frames.iter().map(|&(m, _)| m).collect()),
                )
            }));
        let vv = self.value_volumes;
        // Albedo textures need the rows' maps even without value volumes.
        let with_values = vv.emission || vv.material || vv.maps.albedo;
        // The atlas's texel size (`AtlasScene::new_chunked`): the points' spacing.
        let texel_m = super::atlas::texel_size_for_voxel(grid.voxel_size_m().min_element());
        // The emission sums and volume are half float: they hold the pre-exposed emission.
        let emission_scale = PreExposure::of_scene(scene).store_scale();
        let upload = |name: &str, bytes: &[u8]| {
            let bytes: &[u8] = if bytes.is_empty() { &[0; 80] } else { bytes };
            ctx.upload_buffer(name, bytes, vk::BufferUsageFlags::STORAGE_BUFFER)
        };
        for (o, meshes) in objects {
            self.triangles.push(Vec::new());
            self.values.push(Vec::new());
            for mesh in meshes.unwrap_or_default() {
                let tris = model_triangles(scene, o, mesh);
                let b = upload("atlas triangle attributes", bytemuck::cast_slice(&tris))?;
                if let Some(per_frame) = self.triangles.last_mut() {
                    per_frame.push(b);
                }
                if with_values {
                    let rows = model_values(scene, o, mesh, vv, texel_m, emission_scale);
                    let b = upload("atlas triangle values", bytemuck::cast_slice(&rows))?;
                    if let Some(per_frame) = self.values.last_mut() {
                        per_frame.push(b);
                    }
                }
            }
        }
        if !(statics_once && atlas.has_static()) {
            return Ok(());
        }
        let ext = grid.extent_voxels();
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        let resting = VOLUME_STATE.info().layout;
        let sums = |name: &str| -> Result<Image, VkError> {
            let desc = ImageDesc::new_2d(name, SUM_FORMAT, ext.x, ext.y)
                .with_layers(ext.z)
                .with_usage(
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_DST,
                );
            let image = ctx.create_image(&desc)?;
            ctx.clear_new_image(&image, zero, resting)?;
            Ok(image)
        };
        let images = SumImages {
            albedo: sums("atlas static albedo sums")?,
            normal: sums("atlas static normal sums")?,
            emission: vv
                .emission
                .then(|| sums("atlas static emission sums"))
                .transpose()?,
            material: vv
                .material
                .then(|| sums("atlas static material sums"))
                .transpose()?,
        };
        let mut g = RenderGraph::new();
        let targets = import_sums(&mut g, &images);
        self.static_sums = Some(images);
        let splats = self.splats(&mut g, atlas, true, false);
        let maps = self.import_maps(&mut g);
        add_splat_pass(&mut g, *self.splat, grid, targets, (splats, maps), None);
        run_once(ctx, g)?;
        Ok(())
    }

    /// Imports the maps' texels and table for the splat's vertex shader.
    fn import_maps(&self, g: &mut RenderGraph) -> Option<(BufferHandle, BufferHandle)> {
        self.maps
            .as_ref()
            .map(|m| m.import(g, Access::StorageRead(Shader::Graphics)))
    }

    /// Imports the point and triangle buffers of the static and/or dynamic instances.
    fn splats(
        &self,
        g: &mut RenderGraph,
        atlas: &AtlasScene,
        statics: bool,
        dynamics: bool,
    ) -> Vec<Splat> {
        let read = Access::StorageRead(Shader::Graphics);
        // Instance i of `instances(true, true)` is `self.triangles[i]`.
        let first = if statics {
            0
        } else {
            atlas.static_instances.len()
        };
        atlas
            .instances(statics, dynamics)
            .into_iter()
            .zip(self.triangles.iter().skip(first))
            .zip(self.values.iter().skip(first))
            .filter(|((inst, _), _)| inst.frames.iter().any(|p| p.count > 0))
            .map(|((inst, tris), values)| Splat {
                frames: inst
                    .frames
                    .iter()
                    .enumerate()
                    .zip(tris)
                    .map(|((f, p), t)| {
                        let t = g.import_buffer(t, read);
                        let v = values.get(f).map_or(t, |v| g.import_buffer(v, read));
                        let c = inst.coverage.get(f).copied().flatten();
                        let c = c.map(|c| g.import_buffer(&c.buffer, read));
                        (import_chunks(g, p, read), t, v, c)
                    })
                    .collect(),
                frame: inst.frame,
                model: inst.model,
            })
            .collect()
    }

    /// Prepares frame slot `slot` (before recording it): without a slot gate, the resolve
    /// records in the first frame only.
    pub fn prepare(&mut self, slot: usize) {
        let first = !std::mem::replace(&mut self.resolved, true);
        self.resolve_once.set(slot, first);
    }

    /// Declares this frame's `voxelize_atlas_volumes` (the dynamic instances, and the static
    /// ones when `statics_per_frame`), `voxelize_atlas_resolve` into the volumes `v`'s albedo
    /// and normal (imported [`AttributeVolumes`]) and, with value volumes,
    /// `voxelize_atlas_emission` / `voxelize_atlas_material` into theirs. With a `gate`, all
    /// record only in the slots that re-voxelize the bits; without one (nothing moves) the
    /// first frame resolves, once.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        (atlas, grid): (&AtlasScene, &VoxelGrid),
        v: &AttributeHandles,
        statics_per_frame: bool,
        gate: Option<Arc<SlotGate>>,
    ) {
        let ext = grid.extent_voxels();
        let vv = self.value_volumes;
        let splats = self.splats(g, atlas, statics_per_frame, true);
        let frame_sums = if splats.is_empty() {
            None
        } else {
            let mut sums = |name: &str| {
                g.create_image(ImageDesc::new_2d(name, SUM_FORMAT, ext.x, ext.y).with_layers(ext.z))
            };
            let targets = Sums {
                albedo: sums("atlas albedo sums"),
                normal: sums("atlas normal sums"),
                emission: vv.emission.then(|| sums("atlas emission sums")),
                material: vv.material.then(|| sums("atlas material sums")),
            };
            let maps = self.import_maps(g);
            add_splat_pass(g, *self.splat, grid, targets, (splats, maps), gate.clone());
            Some(targets)
        };
        let static_sums = self.static_sums.as_ref().map(|s| import_sums(g, s));
        let Some(first) = static_sums.or(frame_sums) else {
            return;
        };
        let second = frame_sums.unwrap_or(first);
        let push = GpuAtlasResolvePush {
            dims: [
                ext.x,
                ext.y,
                ext.z,
                u32::from(static_sums.is_some()) | (u32::from(frame_sums.is_some()) << 1),
            ],
        };
        let (pipe, sampler, c) = (*self.resolve, self.sampler.raw, Shader::Compute);
        // Without a slot gate (nothing ever moves) the first frame resolves, once.
        let gate = gate.unwrap_or_else(|| self.resolve_once.clone());
        let dispatch = move |ctx: &crate::graph::PassContext<'_>, pipe| {
            ctx.bind(&pipe);
            ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
            ctx.cmd
                .dispatch(ext.x.div_ceil(8), ext.y.div_ceil(8), ext.z);
        };
        g.add_pass("voxelize_atlas_resolve")
            .pipeline(&pipe)
            .bind_sampled(0, first.albedo, sampler, c)
            .bind_sampled(1, first.normal, sampler, c)
            .bind_sampled(2, second.albedo, sampler, c)
            .bind_sampled(3, second.normal, sampler, c)
            .bind(4, v.albedo, Access::StorageWrite(c))
            .bind(5, v.normal, Access::StorageWrite(c))
            .when(Some(gate.clone()))
            .record(move |ctx| dispatch(ctx, pipe));
        if let (Some(resolve), Some(a), Some(b), Some(out)) = (
            &self.emission_resolve,
            first.emission,
            second.emission,
            v.emission,
        ) {
            let pipe = **resolve;
            g.add_pass("voxelize_atlas_emission")
                .pipeline(&pipe)
                .bind_sampled(0, a, sampler, c)
                .bind_sampled(1, b, sampler, c)
                .bind(2, out, Access::StorageWrite(c))
                .when(Some(gate.clone()))
                .record(move |ctx| dispatch(ctx, pipe));
        }
        if let (Some(resolve), Some(a), Some(b), Some(out)) = (
            &self.material_resolve,
            first.material,
            second.material,
            v.material,
        ) {
            let pipe = **resolve;
            g.add_pass("voxelize_atlas_material")
                .pipeline(&pipe)
                .bind_sampled(0, first.albedo, sampler, c)
                .bind_sampled(1, first.normal, sampler, c)
                .bind_sampled(2, a, sampler, c)
                .bind_sampled(3, second.albedo, sampler, c)
                .bind_sampled(4, second.normal, sampler, c)
                .bind_sampled(5, b, sampler, c)
                .bind(6, out, Access::StorageWrite(c))
                .when(Some(gate))
                .record(move |ctx| dispatch(ctx, pipe));
        }
    }
}

/// Imports persistent sum layers in their resting state.
fn import_sums(g: &mut RenderGraph, s: &SumImages) -> Sums {
    let mut import = |i: &Image| g.import_image(i, VOLUME_STATE);
    Sums {
        albedo: import(&s.albedo),
        normal: import(&s.normal),
        emission: s.emission.as_ref().map(&mut import),
        material: s.material.as_ref().map(&mut import),
    }
}

/// Declares `voxelize_atlas_volumes`: clears the sum layers `sums` and draws every splat's
/// points into them, one draw per point-list chunk, sampling the maps' `(texels, table)` when
/// given. Records only in slots `gate` leaves open.
fn add_splat_pass(
    g: &mut RenderGraph,
    pipe: PipelineHandle,
    grid: &VoxelGrid,
    sums: Sums,
    (splats, maps): (Vec<Splat>, Option<(BufferHandle, BufferHandle)>),
    gate: Option<Arc<SlotGate>>,
) {
    let read = Access::StorageRead(Shader::Graphics);
    let mut points = Vec::new();
    let mut tris = Vec::new();
    let mut values = Vec::new();
    // An opaque object's draws bind their points there (never read).
    let mut coverage = Vec::new();
    for (chunks, t, v, c) in splats.iter().flat_map(|s| &s.frames) {
        for &(p, _) in chunks {
            points.push(p);
            tris.push(*t);
            values.push(*v);
            coverage.push(c.unwrap_or(p));
        }
    }
    let grid = *grid;
    // Plain attachment writes: the pass clears on load, so blending reads only what the pass
    // itself wrote, never the contents of an earlier pass. The viewport is the grid's x,y
    // resolution (the sums' extent): a point's raster position is its column.
    let mut pass = g
        .add_pass("voxelize_atlas_volumes")
        .pipeline(&pipe)
        .bind_one_of(0, points, read)
        .bind_one_of(1, tris.clone(), read)
        .bind_one_of(2, values, read)
        .bind_one_of(COVERAGE_BINDING, coverage, read);
    // Without maps the shader never reads bindings 3 and 4: the triangles stand in.
    pass = match maps {
        Some((texels, table)) => pass.bind(3, texels, read).bind(4, table, read),
        None => pass
            .bind_one_of(3, tris.clone(), read)
            .bind_one_of(4, tris, read),
    };
    pass = pass
        .color(sums.albedo, Load::Clear([0.0; 4]))
        .color(sums.normal, Load::Clear([0.0; 4]));
    for s in [sums.emission, sums.material].into_iter().flatten() {
        pass = pass.color(s, Load::Clear([0.0; 4]));
    }
    let with_maps = maps.is_some();
    pass.when(gate).record(move |ctx| {
        ctx.begin_rendering();
        for splat in &splats {
            let f = splat.frame.at(ctx.slot);
            let Some((chunks, tris, values, coverage)) =
                splat.frames.get(f).or(splat.frames.first())
            else {
                continue;
            };
            let model = splat.model.at(ctx.slot);
            // The chunks in list order: blending sums in primitive order across draws
            // too, so the sums equal one draw of the whole list.
            for &(points, count) in chunks {
                if count == 0 {
                    continue;
                }
                let push = GpuAtlasVoxelizePush::new(&grid, model, (0, 0), count)
                    .with_coverage(coverage.is_some());
                let chosen = [
                    (0, points),
                    (1, *tris),
                    (2, *values),
                    (COVERAGE_BINDING, coverage.unwrap_or(points)),
                    (3, *tris),
                    (4, *tris),
                ];
                let n = if with_maps { 4 } else { 6 };
                ctx.bind_with(&pipe, &chosen[..n]);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.draw(count, 1);
            }
        }
        ctx.cmd.end_rendering();
    });
}

/// The material index of every triangle of `mesh` as object `object` draws it (its material
/// overrides first, as the renderer and the triangle voxelizer resolve them).
fn triangle_materials(
    scene: &Scene,
    object: usize,
    mesh: &crate::scene::Mesh,
) -> Vec<Option<usize>> {
    let mut out = vec![None; mesh.indices.len() / 3];
    let Some(o) = scene.objects.get(object) else {
        return out;
    };
    for (si, sub) in mesh.submeshes.iter().enumerate() {
        let material = o.materials.get(si).copied().unwrap_or(sub.material);
        let first = sub.first_index as usize / 3;
        let end = (first + sub.index_count as usize / 3).min(out.len());
        for slot in out.get_mut(first..end).into_iter().flatten() {
            *slot = Some(material);
        }
    }
    out
}

/// Object `object`'s triangles of mesh `mesh` (its mesh, or one of its sequence frames) in
/// model space, each vertex's w holding one channel of its submesh's material albedo (the
/// object's material overrides first, as the renderer and `gi::attribute_triangles` resolve
/// them). Triangle i is the atlas's triangle i.
fn model_triangles(scene: &Scene, object: usize, mesh: usize) -> Vec<[[f32; 4]; 3]> {
    let Some(mesh) = scene.meshes.get(mesh) else {
        return Vec::new();
    };
    let albedo = triangle_materials(scene, object, mesh)
        .into_iter()
        .map(|m| {
            m.and_then(|m| scene.materials.get(m))
                .map_or(Vec3::splat(0.5), |m| m.albedo)
        });
    mesh.indices
        .chunks_exact(3)
        .zip(albedo)
        .map(|(t, a)| {
            [0, 1, 2].map(|k| {
                let p = mesh
                    .positions
                    .get(t[k] as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO);
                [p.x, p.y, p.z, a[k]]
            })
        })
        .collect()
}

/// The values of [`model_triangles`]'s triangles for the value volumes `vv`, five `vec4`s
/// each (`voxelize_atlas_volumes.vert`): emission (`Ke` where `map_Ke` is sampled, else `Ke` ×
/// the map's mean; w 1 for an emissive material), the material texel ([`material_texel`]),
/// then the triangle's [`GpuTriangleMaps`] for points `texel_m` apart (the level of detail
/// comes from the triangle's size in the world: the object's transform at time 0), whose
/// `map_Kd` replaces the triangles' albedo. The emission is multiplied by `emission_scale`, the
/// scene's pre-exposure ([`PreExposure`]).
fn model_values(
    scene: &Scene,
    object: usize,
    mesh: usize,
    vv: ValueVolumes,
    texel_m: f32,
    emission_scale: f32,
) -> Vec<[[f32; 4]; 5]> {
    let (Some(o), Some(mesh)) = (scene.objects.get(object), scene.meshes.get(mesh)) else {
        return Vec::new();
    };
    let model = o.transform_at(0.0);
    let materials = triangle_materials(scene, object, mesh);
    mesh.indices
        .chunks_exact(3)
        .zip(materials)
        .map(|(t, m)| {
            let Some(m) = m.and_then(|m| scene.materials.get(m)) else {
                return [
                    [0.0; 4],
                    [0.0; 4],
                    [0.0; 4],
                    [0.0; 4],
                    GpuTriangleMaps::NONE.to_vec4s()[2],
                ];
            };
            let ids = vv.maps.maps_of(m);
            let emission = if ids[2] >= 0 {
                m.emission
            } else {
                m.voxel_emission(&scene.textures)
            };
            let emission = emission * emission_scale;
            let flag = if m.is_emissive() { 1.0 } else { 0.0 };
            let row = if ids == [-1; 4] {
                GpuTriangleMaps::NONE
            } else {
                let vertex = |k: usize| t[k] as usize;
                let p = [0, 1, 2].map(|k| {
                    model.transform_point3(
                        mesh.positions.get(vertex(k)).copied().unwrap_or(Vec3::ZERO),
                    )
                });
                let uv = [0, 1, 2].map(|k| {
                    mesh.uvs
                        .as_ref()
                        .and_then(|uvs| uvs.get(vertex(k)).copied())
                        .unwrap_or(Vec2::ZERO)
                });
                GpuTriangleMaps::new(ids, p, uv, texel_m)
            };
            let [uv01, uv2_lod, maps] = row.to_vec4s();
            [
                emission.extend(flag).to_array(),
                material_texel(m, &scene.textures),
                uv01,
                uv2_lod,
                maps,
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_push_matches_glsl() {
        assert_eq!(std::mem::size_of::<GpuAtlasResolvePush>(), 16);
    }
}

//! Non-binary atlas voxelization (Thiedemann 2010, §4.3.2): the atlas
//! points that set the bits ([`super::gpu_atlas`]) also write albedo and normal volumes
//! congruent with them, for the GI methods that read more than occupancy (the voxel path
//! tracer and the direct-radiance volume). They exist only when such a method runs
//! ([`super::gpu::VoxelFrame::enable_attribute_volumes`]).
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

use super::gpu::{GpuVoxelError, SlotGate};
use super::gpu_atlas::{import_chunks, AtlasScene, FrameAt, GpuAtlasVoxelizePush, ModelAt};
use super::VoxelGrid;
use crate::graph::run_once;
use crate::graph::{Access, BufferHandle, ImageHandle, Load, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{
    vk, Buffer, ComputePipeline, Context, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    PipelineHandle, VkError,
};
use glam::Vec3;
use std::sync::Arc;

/// Format of the per-voxel sums: f16 counts are exact up to 2048 points per voxel, far more
/// than an atlas sized for the grid puts into one (a few per surface crossing it).
pub const SUM_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Formats of the resolved volumes (what `gi_pathtrace.comp` samples).
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const NORMAL_FORMAT: vk::Format = vk::Format::R8G8B8A8_SNORM;

/// State of the resolved volumes between frames: sampled by compute shaders.
pub const VOLUME_STATE: Access = Access::Sampled(Shader::Compute);

/// Push constants of `voxelize_atlas_resolve.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAtlasResolvePush {
    /// `res_x, res_y, D`, and bit 0: static sums bound, bit 1: frame sums bound.
    pub dims: [u32; 4],
}

crate::push_constants!(GpuAtlasResolvePush { dims });

/// The albedo (`RGBA8`, a = 1 where occupied) and normal (`RGBA8_SNORM`) 3D volumes,
/// one texel per voxel, in the voxel grid's (x, y, depth) order.
pub struct AttributeVolumes {
    pub albedo: Image,
    pub normal: Image,
}

impl AttributeVolumes {
    /// Cleared volumes in their resting state [`VOLUME_STATE`].
    pub fn new(ctx: &Context, grid: &VoxelGrid) -> Result<Self, VkError> {
        let ext = grid.extent_voxels();
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        let volume = |name: &str, format| {
            ImageDesc::new_2d(name, format, ext.x, ext.y)
                .with_depth(ext.z)
                .with_usage(usage)
        };
        let resting = VOLUME_STATE.info().layout;
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        let albedo = ctx.create_image(&volume("albedo volume", ALBEDO_FORMAT))?;
        let normal = ctx.create_image(&volume("normal volume", NORMAL_FORMAT))?;
        let me = Self { albedo, normal };
        let cleared = ctx
            .clear_new_image(&me.albedo, zero, resting)
            .and_then(|()| ctx.clear_new_image(&me.normal, zero, resting));
        cleared?;
        Ok(me)
    }

    /// Imports both volumes into `g` in their resting state: `(albedo, normal)`.
    pub fn import(&self, g: &mut RenderGraph) -> (ImageHandle, ImageHandle) {
        (
            g.import_image(&self.albedo, VOLUME_STATE),
            g.import_image(&self.normal, VOLUME_STATE),
        )
    }
}

/// Pipelines, per-instance triangle attributes and the static objects' sums.
pub struct AtlasVolumes {
    splat: GraphicsPipeline,
    resolve: ComputePipeline,
    sampler: crate::vk::Sampler,
    /// Per instance (static instances first, then dynamic, as in [`AtlasScene`]) and per
    /// sequence frame (one for rigid objects): the frame's triangles in model space with
    /// the object's material albedo in the vertices' w (the layout of
    /// `voxelize_attributes.comp`), indexed by the points' triangle index. Per frame because
    /// a deforming frame turns its faces (the normals follow).
    triangles: Vec<Vec<Buffer>>,
    /// `(albedo sums, normal sums)` of the static instances, splatted once; absent when the
    /// statics are splatted every frame (`revoxelize_static`) or there are none.
    static_sums: Option<(Image, Image)>,
    /// Without a slot gate (nothing ever moves) the volumes are resolved by the first frame:
    /// open in the slot of the first [`Self::prepare`], closed after.
    resolve_once: Arc<SlotGate>,
    /// [`Self::prepare`] has opened a first frame.
    resolved: bool,
}

/// A draw of one instance: per sequence frame its point chunks `(points, count)` and its
/// triangles, and which frame and model matrix a slot uses.
struct Splat {
    frames: Vec<(Vec<(BufferHandle, u32)>, BufferHandle)>,
    frame: FrameAt,
    model: ModelAt,
}

impl AtlasVolumes {
    /// Builds the pipelines and triangle attributes of `atlas`'s instances and, when
    /// `statics_once`, splats the static instances once.
    pub fn new(
        ctx: &Context,
        atlas: &AtlasScene,
        scene: &Scene,
        grid: &VoxelGrid,
        statics_once: bool,
    ) -> Result<Self, GpuVoxelError> {
        let mut desc = GraphicsPipelineDesc::fullscreen(
            "voxelize_atlas_volumes.vert",
            "voxelize_atlas_volumes.frag",
            SUM_FORMAT,
        );
        desc.geometry = Some("voxelize_atlas_volumes.geom".into());
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.color_formats = vec![SUM_FORMAT, SUM_FORMAT];
        desc.push = crate::vk::PushLayout::of::<GpuAtlasVoxelizePush>();
        let splat = ctx.graphics_pipeline_additive(&desc)?;
        let resolve = ctx.compute_pipeline(
            "voxelize_atlas_resolve.comp",
            crate::vk::PushLayout::of::<GpuAtlasResolvePush>(),
            &[],
        );
        let mut me = Self {
            splat,
            resolve: resolve?,
            sampler: ctx.create_sampler(vk::Filter::NEAREST, false)?,
            triangles: Vec::new(),
            static_sums: None,
            resolve_once: Arc::new(SlotGate::default()),
            resolved: false,
        };
        me.init(ctx, atlas, scene, grid, statics_once)?;
        Ok(me)
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
        for (o, meshes) in objects {
            let mut per_frame = Vec::new();
            for mesh in meshes.unwrap_or_default() {
                let tris = model_triangles(scene, o, mesh);
                let bytes: &[u8] = if tris.is_empty() {
                    &[0; 48]
                } else {
                    bytemuck::cast_slice(&tris)
                };
                let b = ctx.upload_buffer(
                    "atlas triangle attributes",
                    bytes,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                );
                match b {
                    Ok(b) => per_frame.push(b),
                    Err(e) => {
                        self.triangles.push(per_frame);
                        return Err(e.into());
                    }
                }
            }
            self.triangles.push(per_frame);
        }
        if !(statics_once && atlas.has_static()) {
            return Ok(());
        }
        let ext = grid.extent_voxels();
        let sums = |name: &str| {
            ImageDesc::new_2d(name, SUM_FORMAT, ext.x, ext.y)
                .with_layers(ext.z)
                .with_usage(
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_DST,
                )
        };
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        let resting = VOLUME_STATE.info().layout;
        let albedo = ctx.create_image(&sums("atlas static albedo sums"))?;
        let normal = ctx.create_image(&sums("atlas static normal sums"))?;
        self.static_sums = Some((albedo, normal));
        let Some((albedo, normal)) = &self.static_sums else {
            return Ok(());
        };
        ctx.clear_new_image(albedo, zero, resting)?;
        ctx.clear_new_image(normal, zero, resting)?;
        let mut g = RenderGraph::new();
        let targets = (
            g.import_image(albedo, VOLUME_STATE),
            g.import_image(normal, VOLUME_STATE),
        );
        let splats = self.splats(&mut g, atlas, true, false);
        add_splat_pass(&mut g, *self.splat, grid, targets, splats, None);
        run_once(ctx, g)?;
        Ok(())
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
            .filter(|(inst, _)| inst.frames.iter().any(|p| p.count > 0))
            .map(|(inst, tris)| Splat {
                frames: inst
                    .frames
                    .iter()
                    .zip(tris)
                    .map(|(p, t)| (import_chunks(g, p, read), g.import_buffer(t, read)))
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
    /// ones when `statics_per_frame`) and `voxelize_atlas_resolve` into `albedo` and `normal`
    /// (imported [`AttributeVolumes`]). With a `gate`, both record only in the slots that
    /// re-voxelize the bits; without one (nothing moves) the first frame resolves, once.
    #[allow(clippy::too_many_arguments)]
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        atlas: &AtlasScene,
        grid: &VoxelGrid,
        albedo: ImageHandle,
        normal: ImageHandle,
        statics_per_frame: bool,
        gate: Option<Arc<SlotGate>>,
    ) {
        let ext = grid.extent_voxels();
        let splats = self.splats(g, atlas, statics_per_frame, true);
        let frame_sums = if splats.is_empty() {
            None
        } else {
            let mut sums = |name: &str| {
                g.create_image(ImageDesc::new_2d(name, SUM_FORMAT, ext.x, ext.y).with_layers(ext.z))
            };
            let targets = (sums("atlas albedo sums"), sums("atlas normal sums"));
            add_splat_pass(g, *self.splat, grid, targets, splats, gate.clone());
            Some(targets)
        };
        let static_sums = self.static_sums.as_ref().map(|(a, n)| {
            (
                g.import_image(a, VOLUME_STATE),
                g.import_image(n, VOLUME_STATE),
            )
        });
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
        g.add_pass("voxelize_atlas_resolve")
            .pipeline(&pipe)
            .bind_sampled(0, first.0, sampler, c)
            .bind_sampled(1, first.1, sampler, c)
            .bind_sampled(2, second.0, sampler, c)
            .bind_sampled(3, second.1, sampler, c)
            .bind(4, albedo, Access::StorageWrite(c))
            .bind(5, normal, Access::StorageWrite(c))
            .when(Some(gate))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd
                    .dispatch(ext.x.div_ceil(8), ext.y.div_ceil(8), ext.z);
            });
    }
}

/// Declares `voxelize_atlas_volumes`: clears the sum layers `(albedo, normal)` and draws
/// every splat's points into them, one draw per point-list chunk. Records only in slots `gate` leaves open.
fn add_splat_pass(
    g: &mut RenderGraph,
    pipe: PipelineHandle,
    grid: &VoxelGrid,
    (albedo, normal): (ImageHandle, ImageHandle),
    splats: Vec<Splat>,
    gate: Option<Arc<SlotGate>>,
) {
    let read = Access::StorageRead(Shader::Graphics);
    let (points, tris): (Vec<BufferHandle>, Vec<BufferHandle>) = splats
        .iter()
        .flat_map(|s| &s.frames)
        .flat_map(|(chunks, t)| chunks.iter().map(move |&(p, _)| (p, *t)))
        .unzip();
    let grid = *grid;
    // Plain attachment writes: the pass clears on load, so blending reads only what the pass
    // itself wrote, never the contents of an earlier pass. The viewport is the grid's x,y
    // resolution (the sums' extent): a point's raster position is its column.
    g.add_pass("voxelize_atlas_volumes")
        .pipeline(&pipe)
        .bind_one_of(0, points, read)
        .bind_one_of(1, tris, read)
        .color(albedo, Load::Clear([0.0; 4]))
        .color(normal, Load::Clear([0.0; 4]))
        .when(gate)
        .record(move |ctx| {
            ctx.begin_rendering();
            for splat in &splats {
                let f = splat.frame.at(ctx.slot);
                let Some((chunks, tris)) = splat.frames.get(f).or(splat.frames.first()) else {
                    continue;
                };
                let model = splat.model.at(ctx.slot);
                // The chunks in list order: blending sums in primitive order across draws
                // too, so the sums equal one draw of the whole list.
                for &(points, count) in chunks {
                    if count == 0 {
                        continue;
                    }
                    let push = GpuAtlasVoxelizePush::new(&grid, model, (0, 0), count);
                    ctx.bind_with(&pipe, &[(0, points), (1, *tris)]);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd.draw(count, 1);
                }
            }
            ctx.cmd.end_rendering();
        });
}

/// Object `object`'s triangles of mesh `mesh` (its mesh, or one of its sequence frames) in
/// model space, each vertex's w holding one channel of its submesh's material albedo (the
/// object's material overrides first, as the renderer and `gi::attribute_triangles` resolve
/// them). Triangle i is the atlas's triangle i.
fn model_triangles(scene: &Scene, object: usize, mesh: usize) -> Vec<[[f32; 4]; 3]> {
    let Some(o) = scene.objects.get(object) else {
        return Vec::new();
    };
    let Some(mesh) = scene.meshes.get(mesh) else {
        return Vec::new();
    };
    let mut albedo = vec![Vec3::splat(0.5); mesh.indices.len() / 3];
    for (si, sub) in mesh.submeshes.iter().enumerate() {
        let material = o.materials.get(si).copied().unwrap_or(sub.material);
        let a = scene
            .materials
            .get(material)
            .map_or(Vec3::splat(0.5), |m| m.albedo);
        let first = sub.first_index as usize / 3;
        let end = (first + sub.index_count as usize / 3).min(albedo.len());
        for slot in albedo.get_mut(first..end).into_iter().flatten() {
            *slot = a;
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_push_matches_glsl() {
        assert_eq!(std::mem::size_of::<GpuAtlasResolvePush>(), 16);
    }
}

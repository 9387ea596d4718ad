//! Albedo and normal volumes congruent with the bit grid, written from triangles
//! (docs/ARCHITECTURE.md, "The voxel representation": non-binary volumes exist only when something
//! reads them): for the GI methods that read volumes (`gi::GiPasses`, for the objects the atlas
//! voxelizer does not handle; [`super::gpu_atlas_volumes`] writes the others) and for the albedo
//! debug view.
//!
//! Pass `voxelize_attributes` (`glsl/voxelize_attributes.comp`) visits the voxels of the bits'
//! exact conservative test (both shaders include `voxelize_core.glsl`); each voxel keeps the
//! smallest index of the triangles touching it (atomic min on an owner volume). Pass
//! `voxelize_attributes_resolve` then stores the owner's material albedo (RGBA8 UNORM) and
//! world-space face normal (RGBA8 SNORM) and resets the owners. "Last writer wins" instead
//! made a voxel shared by two triangles (a cube standing on a floor) depend on the order the
//! GPU ran them, so two renders of one scene differed. Both passes run in the first frame, and
//! again in a frame whose moving objects moved.

use super::gpu::{voxelize_loads, voxelize_splits, GpuVoxelizePush};
use super::gpu_atlas_volumes::AttributeVolumes;
use super::VoxelGrid;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader, SlotCondition};
use crate::scene::Scene;
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, Image, ImageDesc, MemoryLocation, VkError,
    MAX_FRAMES_IN_FLIGHT,
};
use glam::Vec3;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// State of both volumes between frames: sampled by compute shaders.
pub const ATTRIBUTE_VOLUME_STATE: Access = super::gpu_atlas_volumes::VOLUME_STATE;

/// Group size of the attribute voxelizer (one workgroup per triangle).
const ATTRIBUTE_GROUP_SIZE: u32 = 64;

/// Owner volume value of a voxel no triangle touches.
const NO_OWNER: u32 = u32::MAX;

/// The owner volume rests between rewrites as the resolve pass left it: all [`NO_OWNER`].
const OWNER_STATE: Access = Access::StorageReadWrite(Shader::Compute);

/// A triangle as `voxelize_attributes.comp` reads it: world-space vertices, the w of vertex
/// i = the material albedo's channel i.
type AttributeTriangle = [[f32; 4]; 3];

/// The triangles, pipelines and owner volume that write the albedo and normal volumes of a
/// scene's objects.
pub struct TriangleAttributes {
    pipeline: ComputePipeline,
    resolve_pipeline: ComputePipeline,
    triangles: Buffer,
    triangle_count: u32,
    /// Workgroups per triangle that keep the voxelizer within lavapipe's loop budget.
    splits: u32,
    push: GpuVoxelizePush,
    /// Per voxel, the smallest index of the triangles touching it ([`NO_OWNER`] between
    /// rewrites).
    owner: Image,
    /// A frame has been prepared to write the volumes ([`Self::update`]'s first call).
    written: bool,
    /// Open in the frame slots that rewrite the volumes: the first frame, and a frame whose
    /// moving objects moved.
    gate: Arc<SlotCondition>,
    /// Scenes with moving objects: triangles per frame slot, rewritten when they change.
    animated: Option<AnimatedTriangles>,
}

/// The attribute triangles of a scene with moving objects: one region of the host-visible
/// triangle buffer per frame slot, written after the slot's fence (see `Renderer::write_frame`).
struct AnimatedTriangles {
    scene: Scene,
    capacity: usize,
    last: Option<Vec<AttributeTriangle>>,
    counts: Arc<[AtomicU32; MAX_FRAMES_IN_FLIGHT]>,
    /// Per slot, workgroups per triangle (see [`attribute_splits`]).
    splits: Arc<[AtomicU32; MAX_FRAMES_IN_FLIGHT]>,
    grid: VoxelGrid,
}

/// Albedo and normal volumes with the triangle writer of the objects the atlas voxelizer does
/// not write (the GI methods that read volumes, the albedo debug view); no writer when the
/// atlas writes them all.
pub struct TriangleAttributeVolumes {
    pub volumes: AttributeVolumes,
    pub writer: Option<TriangleAttributes>,
}

impl TriangleAttributeVolumes {
    /// `atlas_writes`: the atlas voxelizer writes the attributes of the objects it handles
    /// ([`super::gpu::VoxelFrame::enable_attribute_volumes`]).
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        grid: &VoxelGrid,
        atlas_writes: bool,
    ) -> Result<Self, VkError> {
        let mut tri_scene = scene.clone();
        if atlas_writes {
            tri_scene
                .objects
                .retain(|o| !super::gpu_atlas::uses_atlas(scene, o));
        }
        let scene = &tri_scene;
        let volumes = AttributeVolumes::new(ctx, grid)?;
        if scene.objects.is_empty() {
            return Ok(Self {
                volumes,
                writer: None,
            });
        }
        match TriangleAttributes::new(ctx, scene, time_s, grid) {
            Ok(writer) => Ok(Self {
                volumes,
                writer: Some(writer),
            }),
            Err(e) => {
                volumes.destroy(ctx);
                Err(e)
            }
        }
    }

    /// See [`TriangleAttributes::update`].
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
        self.writer.as_mut().is_some_and(|w| w.update(t_s, slot))
    }

    /// Declares the passes that write the volumes and returns them `(albedo, normal)`:
    /// `atlas` declares the atlas voxelizer's part (its resolve writes every voxel), then the
    /// triangle objects write theirs on top.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        atlas: impl FnOnce(&mut RenderGraph, ImageHandle, ImageHandle),
    ) -> (ImageHandle, ImageHandle) {
        let (albedo, normal) = self.volumes.import(g);
        atlas(g, albedo, normal);
        if let Some(w) = &self.writer {
            w.add_passes(g, albedo, normal);
        }
        (albedo, normal)
    }

    pub fn destroy(self, ctx: &Context) {
        if let Some(w) = self.writer {
            w.destroy(ctx);
        }
        self.volumes.destroy(ctx);
    }
}

impl TriangleAttributes {
    /// The pipelines and triangles of `scene`'s objects at `time_s` that fill the volumes in
    /// the first frame.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        grid: &VoxelGrid,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "voxelize_attributes.comp",
            crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            &[(0, ATTRIBUTE_GROUP_SIZE)],
        )?;
        let resolve_pipeline =
            match ctx.compute_pipeline("voxelize_attributes_resolve.comp", None, &[]) {
                Ok(p) => p,
                Err(e) => {
                    ctx.destroy_compute_pipeline(pipeline);
                    return Err(e);
                }
            };
        let destroy_pipelines = || {
            ctx.destroy_compute_pipeline(pipeline);
            ctx.destroy_compute_pipeline(resolve_pipeline);
        };
        let tris = attribute_triangles(scene, time_s);
        let bytes: &[u8] = if tris.is_empty() {
            &[0; 48]
        } else {
            bytemuck::cast_slice(&tris)
        };
        let made = if scene.has_animation() {
            // Headroom for OBJ sequences whose frames differ in triangle count.
            let capacity = (tris.len() * 2).max(1);
            let region = (capacity * std::mem::size_of::<AttributeTriangle>()) as u64;
            ctx.create_buffer(&BufferDesc {
                name: "attribute triangles (per frame slot)".into(),
                size_bytes: region * MAX_FRAMES_IN_FLIGHT as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::CpuToGpu,
            })
            .map(|mut buffer| {
                if let Some(m) = buffer.mapped_mut() {
                    for slot in 0..MAX_FRAMES_IN_FLIGHT {
                        let at = slot * region as usize;
                        m[at..at + bytes.len()].copy_from_slice(bytes);
                    }
                }
                let count = tris.len() as u32;
                let splits = attribute_splits(grid, &tris);
                let animated = AnimatedTriangles {
                    scene: scene.clone(),
                    capacity,
                    last: Some(tris.clone()),
                    counts: Arc::new(std::array::from_fn(|_| AtomicU32::new(count))),
                    splits: Arc::new(std::array::from_fn(|_| AtomicU32::new(splits))),
                    grid: *grid,
                };
                (buffer, Some(animated))
            })
        } else {
            ctx.upload_buffer(
                "attribute triangles",
                bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )
            .map(|buffer| (buffer, None))
        };
        let (triangles, animated) = match made {
            Ok(m) => m,
            Err(e) => {
                destroy_pipelines();
                return Err(e);
            }
        };
        let ext = grid.extent_voxels();
        let desc = ImageDesc::new_2d("attribute owner volume", vk::Format::R32_UINT, ext.x, ext.y)
            .with_depth(ext.z)
            .with_usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST);
        let none = vk::ClearColorValue {
            uint32: [NO_OWNER; 4],
        };
        let owner = ctx.create_image(&desc).and_then(|owner| {
            match ctx.clear_new_image(&owner, none, OWNER_STATE.info().layout) {
                Ok(()) => Ok(owner),
                Err(e) => {
                    ctx.destroy_image(owner);
                    Err(e)
                }
            }
        });
        let owner = match owner {
            Ok(o) => o,
            Err(e) => {
                destroy_pipelines();
                ctx.destroy_buffer(triangles);
                return Err(e);
            }
        };
        Ok(Self {
            pipeline,
            resolve_pipeline,
            triangles,
            triangle_count: tris.len() as u32,
            splits: attribute_splits(grid, &tris),
            push: GpuVoxelizePush::new(grid, tris.len() as u32, 0),
            owner,
            written: false,
            gate: Arc::new(SlotCondition::default()),
            animated,
        })
    }

    /// Prepares frame slot `slot` at `t_s` (after the slot's fence, before recording it):
    /// for scenes with moving objects, writes the slot's triangles when they changed; opens
    /// the slot's passes in the first frame and when they changed (and there are triangles),
    /// closes them otherwise. Returns whether the triangles changed.
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
        let slot = slot % MAX_FRAMES_IN_FLIGHT;
        let first = !std::mem::replace(&mut self.written, true);
        let changed = self.rewrite_triangles(t_s, slot);
        let count = self.animated.as_ref().map_or(self.triangle_count, |a| {
            a.counts[slot].load(Ordering::SeqCst)
        });
        self.gate.set(slot, (first || changed) && count > 0);
        changed
    }

    /// Writes slot `slot`'s triangles at `t_s` when they differ from the last ones written.
    fn rewrite_triangles(&mut self, t_s: f32, slot: usize) -> bool {
        let Some(a) = &mut self.animated else {
            return false;
        };
        let tris = attribute_triangles(&a.scene, t_s);
        if a.last.as_ref() == Some(&tris) {
            return false;
        }
        let n = tris.len().min(a.capacity);
        if n < tris.len() {
            log::warn!(
                "{} attribute triangles exceed the buffer's {}; extra ones are dropped",
                tris.len(),
                a.capacity
            );
        }
        let region = a.capacity * std::mem::size_of::<AttributeTriangle>();
        if let Some(m) = self.triangles.mapped_mut() {
            let bytes: &[u8] = bytemuck::cast_slice(&tris[..n]);
            m[slot * region..slot * region + bytes.len()].copy_from_slice(bytes);
        }
        a.counts[slot].store(n as u32, Ordering::SeqCst);
        a.splits[slot].store(attribute_splits(&a.grid, &tris[..n]), Ordering::SeqCst);
        a.last = Some(tris);
        true
    }

    /// Declares `voxelize_attributes` and `voxelize_attributes_resolve`, writing the voxels of
    /// this writer's triangles into `albedo` and `normal` (other voxels keep their values).
    /// The passes record in the slots [`Self::update`] opened: the first frame, and a frame
    /// whose moving objects moved; otherwise the volumes keep their contents.
    pub fn add_passes(&self, g: &mut RenderGraph, albedo: ImageHandle, normal: ImageHandle) {
        let (read, rw) = (
            Access::StorageRead(Shader::Compute),
            Access::StorageReadWrite(Shader::Compute),
        );
        let owner = g.import_image(&self.owner, OWNER_STATE);
        // With moving objects each frame slot reads its own region of the buffer.
        let tris = match &self.animated {
            Some(a) => {
                let region = (a.capacity * std::mem::size_of::<AttributeTriangle>()) as u64;
                g.import_buffer_per_slot(&self.triangles, region, region, read)
            }
            None => g.import_buffer(&self.triangles, read),
        };
        let (pipe, count, splits, vpush) =
            (self.pipeline, self.triangle_count, self.splits, self.push);
        let per_slot = self
            .animated
            .as_ref()
            .map(|a| (a.counts.clone(), a.splits.clone()));
        g.add_pass("voxelize_attributes")
            .pipeline(&pipe)
            .bind(0, tris, read)
            .bind(1, owner, rw)
            .when(Some(self.gate.clone()))
            .record(move |ctx| {
                let slot = ctx.slot % MAX_FRAMES_IN_FLIGHT;
                let (count, splits) = match &per_slot {
                    Some((counts, slot_splits)) => (
                        counts[slot].load(Ordering::SeqCst),
                        slot_splits[slot].load(Ordering::SeqCst),
                    ),
                    None => (count, splits),
                };
                let mut vpush = vpush;
                vpush.extent[2] = count;
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&vpush));
                let x = count.min(65_535);
                ctx.cmd.dispatch(x, count.div_ceil(x), splits);
            });
        let resolve = self.resolve_pipeline;
        let d = &self.owner.desc;
        let extent = (d.width, d.height, d.depth);
        g.add_pass("voxelize_attributes_resolve")
            .pipeline(&resolve)
            .bind(0, tris, read)
            .bind(1, owner, rw)
            .bind(2, albedo, rw)
            .bind(3, normal, rw)
            .when(Some(self.gate.clone()))
            .record(move |ctx| {
                ctx.bind(&resolve);
                ctx.cmd
                    .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), extent.2);
            });
    }

    pub fn destroy(self, ctx: &Context) {
        ctx.destroy_compute_pipeline(self.pipeline);
        ctx.destroy_compute_pipeline(self.resolve_pipeline);
        ctx.destroy_buffer(self.triangles);
        ctx.destroy_image(self.owner);
    }
}

/// Workgroups per attribute triangle: the triangle voxelizer's z splits (the shaders share
/// `voxelize_core.glsl`, and with it lavapipe's loop budget).
fn attribute_splits(grid: &VoxelGrid, tris: &[AttributeTriangle]) -> u32 {
    let loads = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| Vec3::new(v[0], v[1], v[2]));
            voxelize_loads(grid, a.min(b).min(c), a.max(b).max(c))
        })
        .max()
        .unwrap_or(0);
    voxelize_splits(loads, ATTRIBUTE_GROUP_SIZE)
}

/// Every triangle of `scene` at `t_s` with its material's albedo.
fn attribute_triangles(scene: &Scene, t_s: f32) -> Vec<AttributeTriangle> {
    let mut out = Vec::new();
    for object in &scene.objects {
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let m = object.transform_at(t_s);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let albedo = scene
                .materials
                .get(material)
                .map(|m| m.albedo)
                .unwrap_or(Vec3::splat(0.5));
            let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
            for t in mesh.indices[range].chunks_exact(3) {
                out.push([0, 1, 2].map(|k| {
                    let v = m.transform_point3(mesh.positions[t[k] as usize]);
                    [v.x, v.y, v.z, albedo[k]]
                }));
            }
        }
    }
    out
}

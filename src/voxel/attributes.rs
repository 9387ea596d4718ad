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
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, Descriptor, Image, ImageDesc, MemoryLocation,
    VkError, MAX_FRAMES_IN_FLIGHT,
};
use glam::Vec3;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
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
    /// The volumes hold the static scene once written.
    written: Arc<AtomicBool>,
    /// Scenes with moving objects: triangles per frame slot, rewritten when they change.
    animated: Option<AnimatedTriangles>,
}

/// The attribute triangles of a scene with moving objects: one region of the host-visible
/// triangle buffer per frame slot, written after the slot's fence (see `Renderer::write_frame`).
struct AnimatedTriangles {
    scene: Scene,
    capacity: usize,
    last: Option<Vec<AttributeTriangle>>,
    /// Per slot: the region changed and the volumes must be rewritten in that slot's frame.
    dirty: Arc<[AtomicBool; MAX_FRAMES_IN_FLIGHT]>,
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
                    dirty: Arc::new(std::array::from_fn(|_| AtomicBool::new(false))),
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
            written: Arc::new(AtomicBool::new(false)),
            animated,
        })
    }

    /// For scenes with moving objects: writes frame slot `slot`'s triangles at `t_s` when they
    /// changed, so that frame rewrites the volumes. Returns whether they changed.
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
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
        let slot = slot % MAX_FRAMES_IN_FLIGHT;
        let region = a.capacity * std::mem::size_of::<AttributeTriangle>();
        if let Some(m) = self.triangles.mapped_mut() {
            let bytes: &[u8] = bytemuck::cast_slice(&tris[..n]);
            m[slot * region..slot * region + bytes.len()].copy_from_slice(bytes);
        }
        a.counts[slot].store(n as u32, Ordering::SeqCst);
        a.splits[slot].store(attribute_splits(&a.grid, &tris[..n]), Ordering::SeqCst);
        a.dirty[slot].store(true, Ordering::SeqCst);
        a.last = Some(tris);
        true
    }

    /// Declares `voxelize_attributes` and `voxelize_attributes_resolve`, writing the voxels of
    /// this writer's triangles into `albedo` and `normal` (other voxels keep their values).
    /// The passes record in the first frame, and in a frame whose slot [`Self::update`]
    /// rewrote; otherwise the volumes keep their contents.
    pub fn add_passes(&self, g: &mut RenderGraph, albedo: ImageHandle, normal: ImageHandle) {
        let owner = g.import_image(&self.owner, OWNER_STATE);
        let tris = g.import_buffer(&self.triangles, Access::StorageRead(Shader::Compute));
        let (pipe, count, splits, vpush) =
            (self.pipeline, self.triangle_count, self.splits, self.push);
        let written = self.written.clone();
        let per_slot = self.animated.as_ref().map(|a| {
            let region = (a.capacity * std::mem::size_of::<AttributeTriangle>()) as u64;
            (region, a.dirty.clone(), a.counts.clone(), a.splits.clone())
        });
        let region = per_slot.as_ref().map(|p| p.0);
        // What `voxelize_attributes` decided this frame, for the resolve pass after it.
        let rewrite = Arc::new(AtomicBool::new(false));
        let rewrite_read = rewrite.clone();
        g.add_pass("voxelize_attributes")
            .read(tris, Access::StorageRead(Shader::Compute))
            .write(owner, Access::StorageReadWrite(Shader::Compute))
            .record(move |ctx| {
                rewrite.store(false, Ordering::SeqCst);
                let first = !written.swap(true, Ordering::SeqCst);
                let slot = ctx.slot % MAX_FRAMES_IN_FLIGHT;
                let (count, splits) = match &per_slot {
                    Some((_, dirty, counts, slot_splits)) => {
                        let moved = dirty[slot].swap(false, Ordering::SeqCst);
                        if !(first || moved) {
                            return;
                        }
                        (
                            counts[slot].load(Ordering::SeqCst),
                            slot_splits[slot].load(Ordering::SeqCst),
                        )
                    }
                    None if first => (count, splits),
                    None => return,
                };
                if count == 0 {
                    return;
                }
                rewrite.store(true, Ordering::SeqCst);
                let mut vpush = vpush;
                vpush.extent[2] = count;
                ctx.cmd.bind(
                    &pipe,
                    &[
                        triangle_descriptor(ctx.buffer(tris).raw, region, slot),
                        Descriptor::StorageImage {
                            binding: 1,
                            view: ctx.image(owner).view,
                        },
                    ],
                );
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&vpush));
                let x = count.min(65_535);
                ctx.cmd.dispatch(x, count.div_ceil(x), splits);
            });
        let resolve = self.resolve_pipeline;
        let d = &self.owner.desc;
        let extent = (d.width, d.height, d.depth);
        g.add_pass("voxelize_attributes_resolve")
            .read(tris, Access::StorageRead(Shader::Compute))
            .write(owner, Access::StorageReadWrite(Shader::Compute))
            .write(albedo, Access::StorageReadWrite(Shader::Compute))
            .write(normal, Access::StorageReadWrite(Shader::Compute))
            .record(move |ctx| {
                if !rewrite_read.load(Ordering::SeqCst) {
                    return;
                }
                let slot = ctx.slot % MAX_FRAMES_IN_FLIGHT;
                let storage = |binding, h| Descriptor::StorageImage {
                    binding,
                    view: ctx.image(h).view,
                };
                ctx.cmd.bind(
                    &resolve,
                    &[
                        triangle_descriptor(ctx.buffer(tris).raw, region, slot),
                        storage(1, owner),
                        storage(2, albedo),
                        storage(3, normal),
                    ],
                );
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

/// The triangles a frame's passes read: the whole buffer, or frame slot `slot`'s region of
/// `region` bytes in scenes with moving objects.
fn triangle_descriptor(buffer: vk::Buffer, region: Option<u64>, slot: usize) -> Descriptor {
    match region {
        Some(region) => Descriptor::StorageBuffer {
            binding: 0,
            buffer,
            offset: slot as u64 * region,
            range: region,
        },
        None => Descriptor::storage_buffer(0, buffer),
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

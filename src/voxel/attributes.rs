//! Albedo and normal volumes congruent with the bit grid, written from triangles, for the
//! albedo debug view (DESIGN.md "Voxel representation": non-binary volumes exist only when
//! something reads them). Nothing else creates them.
//!
//! Pass `voxelize_attributes` (`glsl/voxelize_attributes.comp`) sets the voxels of the bits'
//! exact conservative test (both shaders include `voxelize_core.glsl`); each stores its
//! triangle's material albedo (RGBA8 UNORM) and world-space face normal (RGBA8 SNORM). It runs
//! in the first frame, and again in a frame whose moving objects moved.
//!
//! The GI methods' volumes (`gi::PathTracer`, with the atlas voxelizer's part from
//! [`super::gpu_atlas_volumes`]) still carry their own copy of this triangle pass; moving it
//! onto this type is open.

use super::gpu::{voxelize_loads, voxelize_splits, GpuVoxelizePush};
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
pub const ATTRIBUTE_VOLUME_STATE: Access = Access::Sampled(Shader::Compute);

/// Group size of the attribute voxelizer (one workgroup per triangle).
const ATTRIBUTE_GROUP_SIZE: u32 = 64;

/// A triangle as `voxelize_attributes.comp` reads it: world-space vertices, the w of vertex
/// i = the material albedo's channel i.
type AttributeTriangle = [[f32; 4]; 3];

/// The albedo and normal volumes with the triangles and pipeline that write them.
pub struct TriangleAttributeVolumes {
    pipeline: ComputePipeline,
    triangles: Buffer,
    triangle_count: u32,
    /// Workgroups per triangle that keep the voxelizer within lavapipe's loop budget.
    splits: u32,
    push: GpuVoxelizePush,
    albedo: Image,
    normal: Image,
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

impl TriangleAttributeVolumes {
    /// Cleared volumes for `grid` and the pipeline and triangles of `scene` at `time_s` that
    /// fill them in the first frame.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        grid: &VoxelGrid,
    ) -> Result<Self, VkError> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let image = vk::DescriptorType::STORAGE_IMAGE;
        let pipeline = ctx.compute_pipeline(
            "voxelize_attributes.comp",
            &[(0, storage), (1, image), (2, image)],
            std::mem::size_of::<GpuVoxelizePush>() as u32,
            &[(0, ATTRIBUTE_GROUP_SIZE)],
        )?;
        let tris = attribute_triangles(scene, time_s);
        let bytes: &[u8] = if tris.is_empty() {
            &[0; 48]
        } else {
            bytemuck::cast_slice(&tris)
        };
        let (triangles, animated) = if scene.has_animation() {
            // Headroom for OBJ sequences whose frames differ in triangle count.
            let capacity = (tris.len() * 2).max(1);
            let region = (capacity * std::mem::size_of::<AttributeTriangle>()) as u64;
            let mut buffer = ctx.create_buffer(&BufferDesc {
                name: "attribute triangles (per frame slot)".into(),
                size_bytes: region * MAX_FRAMES_IN_FLIGHT as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::CpuToGpu,
            })?;
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
        } else {
            let buffer = ctx.upload_buffer(
                "attribute triangles",
                bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?;
            (buffer, None)
        };
        let ext = grid.extent_voxels();
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST;
        let volume = |name: &str, format| {
            ImageDesc::new_2d(name, format, ext.x, ext.y)
                .with_depth(ext.z)
                .with_usage(usage)
        };
        let resting = ATTRIBUTE_VOLUME_STATE.info().layout;
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        let albedo = ctx.create_image(&volume("albedo volume", vk::Format::R8G8B8A8_UNORM))?;
        ctx.clear_new_image(&albedo, zero, resting)?;
        let normal = ctx.create_image(&volume("normal volume", vk::Format::R8G8B8A8_SNORM))?;
        ctx.clear_new_image(&normal, zero, resting)?;
        Ok(Self {
            pipeline,
            triangles,
            triangle_count: tris.len() as u32,
            splits: attribute_splits(grid, &tris),
            push: GpuVoxelizePush::new(grid, tris.len() as u32, 0),
            albedo,
            normal,
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
        let region = a.capacity * std::mem::size_of::<AttributeTriangle>();
        if let Some(m) = self.triangles.mapped_mut() {
            let bytes: &[u8] = bytemuck::cast_slice(&tris[..n]);
            m[slot * region..slot * region + bytes.len()].copy_from_slice(bytes);
        }
        let slot = slot % MAX_FRAMES_IN_FLIGHT;
        a.counts[slot].store(n as u32, Ordering::SeqCst);
        a.splits[slot].store(attribute_splits(&a.grid, &tris[..n]), Ordering::SeqCst);
        a.dirty[slot].store(true, Ordering::SeqCst);
        a.last = Some(tris);
        true
    }

    /// Declares `voxelize_attributes` and returns the `(albedo, normal)` volumes (resting
    /// state [`ATTRIBUTE_VOLUME_STATE`]). The pass records in the first frame, and in a frame
    /// whose slot [`Self::update`] rewrote; otherwise the volumes keep their contents.
    pub fn add_pass(&self, g: &mut RenderGraph) -> (ImageHandle, ImageHandle) {
        let albedo = g.import_image(&self.albedo, ATTRIBUTE_VOLUME_STATE);
        let normal = g.import_image(&self.normal, ATTRIBUTE_VOLUME_STATE);
        let tris = g.import_buffer(&self.triangles, Access::StorageRead(Shader::Compute));
        let (pipe, count, splits, vpush) =
            (self.pipeline, self.triangle_count, self.splits, self.push);
        let written = self.written.clone();
        let per_slot = self.animated.as_ref().map(|a| {
            let region = (a.capacity * std::mem::size_of::<AttributeTriangle>()) as u64;
            (region, a.dirty.clone(), a.counts.clone(), a.splits.clone())
        });
        g.add_pass("voxelize_attributes")
            .read(tris, Access::StorageRead(Shader::Compute))
            .write(albedo, Access::StorageWrite(Shader::Compute))
            .write(normal, Access::StorageWrite(Shader::Compute))
            .record(move |ctx| {
                let first = !written.swap(true, Ordering::SeqCst);
                let slot = ctx.slot % MAX_FRAMES_IN_FLIGHT;
                let (triangles, count, splits) = match &per_slot {
                    Some((region, dirty, counts, slot_splits)) => {
                        let moved = dirty[slot].swap(false, Ordering::SeqCst);
                        if !(first || moved) {
                            return;
                        }
                        let d = Descriptor::StorageBuffer {
                            binding: 0,
                            buffer: ctx.buffer(tris).raw,
                            offset: slot as u64 * region,
                            range: *region,
                        };
                        let n = counts[slot].load(Ordering::SeqCst);
                        (d, n, slot_splits[slot].load(Ordering::SeqCst))
                    }
                    None if first => (
                        Descriptor::storage_buffer(0, ctx.buffer(tris).raw),
                        count,
                        splits,
                    ),
                    None => return,
                };
                if count == 0 {
                    return;
                }
                let mut vpush = vpush;
                vpush.extent[2] = count;
                ctx.cmd.bind(
                    &pipe,
                    &[
                        triangles,
                        Descriptor::StorageImage {
                            binding: 1,
                            view: ctx.image(albedo).view,
                        },
                        Descriptor::StorageImage {
                            binding: 2,
                            view: ctx.image(normal).view,
                        },
                    ],
                );
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&vpush));
                let x = count.min(65_535);
                ctx.cmd.dispatch(x, count.div_ceil(x), splits);
            });
        (albedo, normal)
    }

    pub fn destroy(self, ctx: &Context) {
        ctx.destroy_compute_pipeline(self.pipeline);
        ctx.destroy_buffer(self.triangles);
        ctx.destroy_image(self.albedo);
        ctx.destroy_image(self.normal);
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

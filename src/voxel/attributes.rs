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
//!
//! Scenes with emitters also get an emission volume (`RGBA16F`, W/(m²·sr) leaving the side the
//! face normal points to), written between the two passes by `voxelize_emission` from the same
//! owners, so emissive surfaces send indirect light (the path tracer and the direct-radiance
//! volume read it). The atlas voxelizer has no emission path: in scenes with emitters the
//! triangle writer writes every object's attributes, on top of the atlas's (its exact
//! conservative test touches every voxel the atlas points set). Other scenes have no emission
//! volume, buffer or pass.

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

/// A triangle's emitted radiance as `voxelize_emission.comp` reads it (rgb W/(m²·sr), w unused).
type TriangleEmission = [f32; 4];

/// Format of the emission volume: radiance above 1 W/(m²·sr) must survive.
const EMISSION_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

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
    /// Scenes with emitters: the pass that writes the emission volume.
    emission: Option<EmissionWriter>,
}

/// The `voxelize_emission` pipeline and the emitted radiance per attribute triangle (laid out
/// like the triangle buffer: one region per frame slot for scenes with moving objects).
struct EmissionWriter {
    pipeline: ComputePipeline,
    emissions: Buffer,
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
    /// Emitted radiance per voxel ([`EMISSION_FORMAT`]), only in scenes with emitters.
    pub emission: Option<Image>,
    pub writer: Option<TriangleAttributes>,
}

/// The attribute volumes of one frame's graph.
#[derive(Clone, Copy, Debug)]
pub struct AttributeHandles {
    pub albedo: ImageHandle,
    pub normal: ImageHandle,
    /// Only in scenes with emitters.
    pub emission: Option<ImageHandle>,
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
        // The atlas voxelizer writes no emission: with emitters, triangles write everything.
        let emits = scene.has_emission();
        if atlas_writes && !emits {
            tri_scene
                .objects
                .retain(|o| !super::gpu_atlas::uses_atlas(scene, o));
        }
        let scene = &tri_scene;
        let volumes = AttributeVolumes::new(ctx, grid)?;
        let emission = emits.then(|| emission_volume(ctx, grid)).transpose()?;
        let writer = if scene.objects.is_empty() {
            None
        } else {
            Some(TriangleAttributes::new(ctx, scene, time_s, grid)?)
        };
        Ok(Self {
            volumes,
            emission,
            writer,
        })
    }

    /// See [`TriangleAttributes::update`].
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
        self.writer.as_mut().is_some_and(|w| w.update(t_s, slot))
    }

    /// Declares the passes that write the volumes and returns them: `atlas` declares the atlas
    /// voxelizer's part (its resolve writes every voxel), then the triangle objects write
    /// theirs on top.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        atlas: impl FnOnce(&mut RenderGraph, ImageHandle, ImageHandle),
    ) -> AttributeHandles {
        let (albedo, normal) = self.volumes.import(g);
        let emission = self
            .emission
            .as_ref()
            .map(|e| g.import_image(e, ATTRIBUTE_VOLUME_STATE));
        atlas(g, albedo, normal);
        let out = AttributeHandles {
            albedo,
            normal,
            emission,
        };
        if let Some(w) = &self.writer {
            w.add_passes(g, &out);
        }
        out
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
            ctx.compute_pipeline("voxelize_attributes_resolve.comp", None, &[])?;
        let (tris, emissions) = attribute_triangles(scene, time_s);
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
        let (triangles, animated) = made?;
        let ext = grid.extent_voxels();
        let desc = ImageDesc::new_2d("attribute owner volume", vk::Format::R32_UINT, ext.x, ext.y)
            .with_depth(ext.z)
            .with_usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST);
        let none = vk::ClearColorValue {
            uint32: [NO_OWNER; 4],
        };
        let owner = ctx.create_image(&desc)?;
        ctx.clear_new_image(&owner, none, OWNER_STATE.info().layout)?;
        let capacity = animated.as_ref().map(|a| a.capacity);
        let emission = scene
            .has_emission()
            .then(|| EmissionWriter::new(ctx, &emissions, capacity))
            .transpose()?;
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
            emission,
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
        let (tris, emissions) = attribute_triangles(&a.scene, t_s);
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
        if let Some(w) = &mut self.emission {
            w.write_slot(slot, a.capacity, &emissions[..n]);
        }
        a.counts[slot].store(n as u32, Ordering::SeqCst);
        a.splits[slot].store(attribute_splits(&a.grid, &tris[..n]), Ordering::SeqCst);
        a.last = Some(tris);
        true
    }

    /// Declares `voxelize_attributes`, (with emitters) `voxelize_emission` and
    /// `voxelize_attributes_resolve`, writing the voxels of this writer's triangles into the
    /// volumes `v` (other voxels keep their values). The passes record in the slots
    /// [`Self::update`] opened: the first frame, and a frame whose moving objects moved;
    /// otherwise the volumes keep their contents.
    pub fn add_passes(&self, g: &mut RenderGraph, v: &AttributeHandles) {
        let (albedo, normal) = (v.albedo, v.normal);
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
            (*self.pipeline, self.triangle_count, self.splits, self.push);
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
        let d = &self.owner.desc;
        let extent = (d.width, d.height, d.depth);
        if let (Some(w), Some(volume)) = (&self.emission, v.emission) {
            let emissions = match &self.animated {
                Some(a) => {
                    let region = (a.capacity * std::mem::size_of::<TriangleEmission>()) as u64;
                    g.import_buffer_per_slot(&w.emissions, region, region, read)
                }
                None => g.import_buffer(&w.emissions, read),
            };
            let pipe = *w.pipeline;
            g.add_pass("voxelize_emission")
                .pipeline(&pipe)
                .bind(0, emissions, read)
                .bind(1, owner, read)
                .bind(2, volume, rw)
                .when(Some(self.gate.clone()))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd
                        .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), extent.2);
                });
        }
        let resolve = *self.resolve_pipeline;
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
}

impl EmissionWriter {
    /// The pipeline and the emissions buffer: one region of `capacity` triangles per frame
    /// slot for scenes with moving objects (`capacity` Some), else just `emissions`.
    fn new(
        ctx: &Context,
        emissions: &[TriangleEmission],
        capacity: Option<usize>,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline("voxelize_emission.comp", None, &[])?;
        let bytes: &[u8] = if emissions.is_empty() {
            &[0; 16]
        } else {
            bytemuck::cast_slice(emissions)
        };
        match capacity {
            Some(capacity) => {
                let region = (capacity * std::mem::size_of::<TriangleEmission>()) as u64;
                ctx.create_buffer(&BufferDesc {
                    name: "attribute emissions (per frame slot)".into(),
                    size_bytes: region * MAX_FRAMES_IN_FLIGHT as u64,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                    location: MemoryLocation::CpuToGpu,
                })
                .map(|buffer| {
                    let mut me = Self {
                        pipeline,
                        emissions: buffer,
                    };
                    for slot in 0..MAX_FRAMES_IN_FLIGHT {
                        me.write_slot(slot, capacity, emissions);
                    }
                    me
                })
            }
            None => ctx
                .upload_buffer(
                    "attribute emissions",
                    bytes,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )
                .map(|emissions| Self {
                    pipeline,
                    emissions,
                }),
        }
    }

    /// Writes frame slot `slot`'s region (of `capacity` triangles) of a per-slot buffer.
    fn write_slot(&mut self, slot: usize, capacity: usize, emissions: &[TriangleEmission]) {
        let region = capacity * std::mem::size_of::<TriangleEmission>();
        let n = emissions.len().min(capacity);
        if let Some(m) = self.emissions.mapped_mut() {
            let bytes: &[u8] = bytemuck::cast_slice(&emissions[..n]);
            m[slot * region..slot * region + bytes.len()].copy_from_slice(bytes);
        }
    }
}

/// A cleared emission volume congruent with `grid`, in [`ATTRIBUTE_VOLUME_STATE`].
fn emission_volume(ctx: &Context, grid: &VoxelGrid) -> Result<Image, VkError> {
    let ext = grid.extent_voxels();
    let desc = ImageDesc::new_2d("emission volume", EMISSION_FORMAT, ext.x, ext.y)
        .with_depth(ext.z)
        .with_usage(
            vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_DST,
        );
    let image = ctx.create_image(&desc)?;
    let zero = vk::ClearColorValue { float32: [0.0; 4] };
    ctx.clear_new_image(&image, zero, ATTRIBUTE_VOLUME_STATE.info().layout)?;
    Ok(image)
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

/// Every triangle of `scene` at `t_s` with its material's albedo, and its material's emission.
fn attribute_triangles(scene: &Scene, t_s: f32) -> (Vec<AttributeTriangle>, Vec<TriangleEmission>) {
    let mut out = Vec::new();
    let mut emissions = Vec::new();
    for object in &scene.objects {
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let m = object.transform_at(t_s);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let (albedo, emission) = scene
                .materials
                .get(material)
                .map_or((Vec3::splat(0.5), Vec3::ZERO), |m| (m.albedo, m.emission));
            let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
            for t in mesh.indices[range].chunks_exact(3) {
                out.push([0, 1, 2].map(|k| {
                    let v = m.transform_point3(mesh.positions[t[k] as usize]);
                    [v.x, v.y, v.z, albedo[k]]
                }));
                emissions.push(emission.extend(0.0).to_array());
            }
        }
    }
    // Emitters own the voxels they share (smallest index wins): a light patch just under a
    // ceiling shares the ceiling's voxels, and must emit from them. A stable partition, so a
    // scene without emitters keeps its order.
    let mut both: Vec<_> = out.into_iter().zip(emissions).collect();
    both.sort_by_key(|(_, e)| e[..3] == [0.0; 3]);
    both.into_iter().unzip()
}

//! Albedo and normal volumes congruent with the bit grid, written from triangles
//! (docs/design/voxels.md: non-binary volumes exist only when something reads them): for the GI methods that read volumes (`gi::GiPasses`, for the objects the atlas
//! voxelizer does not handle; [`super::gpu_atlas_volumes`] writes the others) and for the albedo
//! debug view.
//!
//! Pass `voxelize_attributes` (`glsl/voxelize_attributes.comp`) visits the voxels of the bits'
//! exact conservative test (both shaders include `voxelize_core.glsl`); each voxel keeps the
//! smallest index of the triangles touching it (atomic min on an owner volume). Pass
//! `voxelize_attributes_resolve` then stores the owner's material albedo (RGBA8 UNORM) and
//! world-space face normal (RGBA8 SNORM), with the owner's plane offset from the voxel centre
//! in the normal's w (the path tracer puts its bounce vertices on that plane:
//! `voxel_surface_point` in `glsl/include/gi_common.glsl`), and resets the owners. "Last writer wins" instead
//! made a voxel shared by two triangles (a cube standing on a floor) depend on the order the
//! GPU ran them, so two renders of one scene differed. Both passes run in the first frame, and
//! again in a frame whose moving objects moved.
//!
//! Scenes with emitters also get an emission volume (`RGBA16F`, W/(m²·sr) leaving the side the
//! face normal points to), written between the two passes by `voxelize_emission` from the same
//! owners, so emissive surfaces send indirect light (the path tracer and the direct-radiance
//! volume read it). Other scenes have no emission volume, buffer or pass.
//!
//! Scenes with Phong or GGX materials whose path tracer samples lobes at every bounce also get
//! a material volume (`RGBA16F`, [`material_texel`]), written the same way by
//! `voxelize_material` from the same owners.
//!
//! Both value passes sample the MTL PBR maps (`map_Ke`; `map_Pr`, `map_Pm`) per texel over the
//! owner's part of each voxel ([`super::maps`], `glsl/include/voxel_owner_maps.glsl`)
//! when the scene has them, or take each map's mean with `per_texel` off; so does the resolve
//! with the albedo textures (`map_Kd`, else `Kd`). With the atlas
//! voxelizer its points write all four volumes of the objects it voxelizes
//! ([`super::gpu_atlas_volumes`]), and this writer only the others.

use super::coverage::Coverage;
use super::gpu::{voxelize_loads, voxelize_splits, GpuVoxelizePush};
use super::maps::{owner_sample_spacing_m, GpuTriangleMaps, MapUse, VoxelMaps};
use super::VoxelGrid;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader, SlotCondition};
use crate::scene::{Material, PreExposure, Scene, TextureData};
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, Image, ImageDesc, MemoryLocation, VkError,
    MAX_FRAMES_IN_FLIGHT,
};
use glam::{Vec2, Vec3};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// State of both volumes between frames: sampled by compute shaders.
pub const ATTRIBUTE_VOLUME_STATE: Access = VOLUME_STATE;

/// Group size of the attribute voxelizer (one workgroup per triangle).
const ATTRIBUTE_GROUP_SIZE: u32 = 64;

/// Owner volume value of a voxel no triangle touches.
const NO_OWNER: u32 = u32::MAX;

/// The owner volume rests between rewrites as the resolve pass left it: all [`NO_OWNER`].
const OWNER_STATE: Access = Access::StorageReadWrite(Shader::Compute);

/// A triangle as `voxelize_attributes.comp` reads it: world-space vertices, the w of vertex
/// i = the material albedo's channel i; then the coverage row `[1 − opacity, seed, 0, 0]`
/// ([`Coverage`]), so a pane of opacity below 1 owns only the voxels the bits keep.
type AttributeTriangle = [[f32; 4]; 4];

/// Which value volumes exist besides albedo and normal, and whether they sample the PBR maps
/// per texel; what both voxelizers' value passes are built for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ValueVolumes {
    /// An emission volume (scenes with emitters).
    pub emission: bool,
    /// A material volume (the path tracer's lobes, scenes with Phong or GGX materials).
    pub material: bool,
    /// The maps the volumes sample per texel ([`MapUse`]; none: each map's mean).
    pub maps: MapUse,
}

impl ValueVolumes {
    /// The value volumes of `scene`: emission when it emits, material when asked for
    /// (`material`) and it has lobes; `per_texel` maps where it has them
    /// (`GiSettings::voxel_map_texels`).
    pub fn new(scene: &Scene, material: bool, per_texel: bool) -> Self {
        let emission = scene.has_emission();
        let material = material && !scene.is_all_lambert();
        Self {
            emission,
            material,
            maps: MapUse::new(scene, emission, material, per_texel),
        }
    }
    /// No value volumes, only the albedo volume's `map_Kd` (the albedo debug view).
    pub fn albedo_only(scene: &Scene) -> Self {
        Self {
            maps: MapUse::albedo_only(scene),
            ..Self::default()
        }
    }
}

/// Format of the emission volume (radiance above 1 W/(m²·sr) must survive) and of the material
/// volume (Phong exponents above 1 must survive; 16-bit floats hold every integer exponent up
/// to 2048 exactly, roughness and metalness to 2⁻¹¹).
const VALUE_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The material volume's texel of `m` (`glsl/include/material_lobe.glsl`'s `voxel_lobe` reads
/// it with the albedo volume's color at the same voxel, the base color of GGX materials):
/// Lambert `(0, 0, 0, 0)`; normalized Phong `(ρs, n + 1)` (w ≥ 1); GGX
/// `(roughness, metallic, 0, −1)`.
///
/// GGX parameters are [`Material::voxel_ggx`]'s: a roughness or metalness map enters as its mean.
pub fn material_texel(m: &Material, textures: &[TextureData]) -> [f32; 4] {
    match m.voxel_ggx(textures) {
        Some(g) => [g.roughness, g.metallic, 0.0, -1.0],
        None if m.is_phong() => m.specular.extend(m.shininess + 1.0).to_array(),
        None => [0.0; 4],
    }
}

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
    /// Scenes whose albedo volume samples `map_Kd`: per triangle its [`GpuTriangleMaps`],
    /// which the resolve pass reads.
    albedo_maps: Option<TriangleRows>,
    /// Scenes with emitters: the pass that writes the emission volume.
    emission: Option<OwnerValueWriter>,
    /// With a material volume: the pass that writes it.
    material: Option<OwnerValueWriter>,
    /// The PBR maps the value passes sample per texel, if any.
    maps: Option<VoxelMaps>,
    maps_used: MapUse,
    /// The value passes' sample spacing ([`owner_sample_spacing_m`]).
    spacing_m: f32,
    /// The scene's pre-exposure store scale 2^-k ([`PreExposure`]): the emission volume is
    /// half float, so it holds the emission times this.
    emission_scale: f32,
}

/// The pipeline of a pass that writes one value per owner triangle into a volume
/// (`voxelize_emission`, `voxelize_material`) and the values per attribute triangle (laid out
/// like the triangle buffer: one region per frame slot for scenes with moving objects).
struct OwnerValueWriter {
    /// The pass's name, its shader's file stem.
    name: &'static str,
    pipeline: ComputePipeline,
    values: TriangleRows,
    /// Each triangle's row holds its [`GpuTriangleMaps`] after the value (`HAS_MAPS`).
    with_maps: bool,
}

/// Per-triangle rows of `vec4`s in a storage buffer, laid out like the triangle buffer: one
/// region of `capacity` triangles per frame slot for scenes with moving objects.
struct TriangleRows {
    buffer: Buffer,
    /// `vec4`s per triangle.
    stride: usize,
}

/// The rows of an owner-value buffer: per triangle its value, then (with maps) its
/// [`GpuTriangleMaps`], flattened to `vec4`s.
struct OwnerRows {
    vec4s: Vec<[f32; 4]>,
    /// `vec4`s per triangle: 1, or 4 with maps.
    stride: usize,
}

impl OwnerRows {
    /// Only the maps of each triangle (the resolve pass's albedo maps).
    fn maps(rows: &[GpuTriangleMaps]) -> Self {
        Self {
            vec4s: rows.iter().flat_map(|r| r.to_vec4s()).collect(),
            stride: 3,
        }
    }

    fn new(values: &[([f32; 4], GpuTriangleMaps)], with_maps: bool) -> Self {
        let stride = if with_maps { 4 } else { 1 };
        let mut vec4s = Vec::with_capacity(values.len() * stride);
        for (value, maps) in values {
            vec4s.push(*value);
            if with_maps {
                vec4s.extend(maps.to_vec4s());
            }
        }
        Self { vec4s, stride }
    }
}

/// What an owner-value pass reads and writes besides its values.
#[derive(Clone, Copy)]
struct OwnerInputs {
    owner: ImageHandle,
    volume: ImageHandle,
    /// The attribute triangles (their positions, for the map samples).
    tris: crate::graph::BufferHandle,
    /// The maps' texels and table, when the scene's volumes sample maps.
    maps: Option<(crate::graph::BufferHandle, crate::graph::BufferHandle)>,
    /// The grid (the voxel → world map of the samples).
    push: GpuVoxelizePush,
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
    /// Emitted radiance per voxel ([`VALUE_FORMAT`]), only in scenes with emitters.
    pub emission: Option<Image>,
    /// The material lobe per voxel ([`material_texel`]), only when asked for.
    pub material: Option<Image>,
    pub writer: Option<TriangleAttributes>,
    /// Per object the writer writes, its index in the whole scene.
    indices: Vec<usize>,
}

/// The attribute volumes of one frame's graph.
#[derive(Clone, Copy, Debug)]
pub struct AttributeHandles {
    pub albedo: ImageHandle,
    pub normal: ImageHandle,
    /// Only in scenes with emitters.
    pub emission: Option<ImageHandle>,
    /// Only with a material volume.
    pub material: Option<ImageHandle>,
}

impl TriangleAttributeVolumes {
    /// `atlas_writes`: the atlas voxelizer writes the attributes (and the value volumes) of
    /// the objects it handles ([`super::gpu::VoxelFrame::enable_attribute_volumes`]).
    /// `values`: the emission and material volumes and their maps ([`ValueVolumes::new`]).
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        grid: &VoxelGrid,
        atlas_writes: bool,
        values: ValueVolumes,
    ) -> Result<Self, VkError> {
        let mut tri_scene = scene.clone();
        // Objects the atlas voxelizer handles get every volume from its points.
        let written =
            |o: &crate::scene::Object| !atlas_writes || !super::gpu_atlas::uses_atlas(scene, o);
        let indices = (0..scene.objects.len())
            .filter(|&i| written(&scene.objects[i]))
            .collect();
        tri_scene.objects.retain(written);
        let volumes = AttributeVolumes::new(ctx, grid)?;
        let emission = values
            .emission
            .then(|| value_volume(ctx, grid, "emission volume"))
            .transpose()?;
        let material = values
            .material
            .then(|| value_volume(ctx, grid, "material volume"))
            .transpose()?;
        let writer = if tri_scene.objects.is_empty() {
            None
        } else {
            Some(TriangleAttributes::new(
                ctx, &tri_scene, time_s, grid, values,
            )?)
        };
        Ok(Self {
            volumes,
            emission,
            material,
            writer,
            indices,
        })
    }

    /// Takes the dynamic objects' transforms from `scene` (the scene the volumes were made
    /// for): the next [`Self::update`] writes moved objects' triangles where they now are.
    pub fn follow_objects(&mut self, scene: &Scene) {
        if let Some(a) = self.writer.as_mut().and_then(|w| w.animated.as_mut()) {
            for (o, &i) in a.scene.objects.iter_mut().zip(&self.indices) {
                match scene.objects.get(i) {
                    Some(src) if o.dynamic => o.transform = src.transform,
                    _ => {}
                }
            }
        }
    }

    /// See [`TriangleAttributes::update`].
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
        self.writer.as_mut().is_some_and(|w| w.update(t_s, slot))
    }

    /// Declares the passes that write the volumes and returns them: `atlas` declares the atlas
    /// voxelizer's part (its resolves write every voxel), then the triangle objects write
    /// theirs on top.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        atlas: impl FnOnce(&mut RenderGraph, &AttributeHandles),
    ) -> AttributeHandles {
        let (albedo, normal) = self.volumes.import(g);
        let import = |g: &mut RenderGraph, image: &Option<Image>| {
            image
                .as_ref()
                .map(|e| g.import_image(e, ATTRIBUTE_VOLUME_STATE))
        };
        let emission = import(g, &self.emission);
        let material = import(g, &self.material);
        let out = AttributeHandles {
            albedo,
            normal,
            emission,
            material,
        };
        atlas(g, &out);
        if let Some(w) = &self.writer {
            w.add_passes(g, &out);
        }
        out
    }
}

impl TriangleAttributes {
    /// The pipelines and triangles of `scene`'s objects at `time_s` that fill the volumes in
    /// the first frame; `values`: the writers of the emission and material volumes, and the
    /// maps they sample.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        grid: &VoxelGrid,
        values: ValueVolumes,
    ) -> Result<Self, VkError> {
        let pipeline = ctx.compute_pipeline(
            "voxelize_attributes.comp",
            crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            &crate::spec_constants![local_size_x = ATTRIBUTE_GROUP_SIZE],
        )?;
        let maps_used = values.maps;
        let resolve_pipeline = ctx.compute_pipeline(
            "voxelize_attributes_resolve.comp",
            crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            &crate::spec_constants![HAS_MAPS = maps_used.albedo],
        )?;
        let spacing_m = owner_sample_spacing_m(grid.voxel_size_m());
        let emission_scale = PreExposure::of_scene(scene).store_scale();
        let TriangleValues {
            tris,
            emissions,
            materials,
            albedo_maps,
        } = attribute_triangles(scene, time_s, maps_used, spacing_m, emission_scale);
        let bytes: &[u8] = if tris.is_empty() {
            &[0; 48]
        } else {
            bytemuck::cast_slice(&tris)
        };
        // Dynamic objects (the viewer's editor moves them) are rewritten like animated ones.
        let made = if scene.has_animation() || scene.has_dynamic_objects() {
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
        let albedo_maps = maps_used
            .albedo
            .then(|| {
                let rows = OwnerRows::maps(&albedo_maps);
                TriangleRows::new(ctx, "attribute albedo maps", &rows, capacity)
            })
            .transpose()?;
        let emission = values
            .emission
            .then(|| {
                let rows = OwnerRows::new(&emissions, maps_used.emission);
                OwnerValueWriter::new(ctx, "voxelize_emission", rows, capacity)
            })
            .transpose()?;
        let material = values
            .material
            .then(|| {
                let rows = OwnerRows::new(&materials, maps_used.lobe);
                OwnerValueWriter::new(ctx, "voxelize_material", rows, capacity)
            })
            .transpose()?;
        let maps = VoxelMaps::new(ctx, scene, maps_used)?;
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
            albedo_maps,
            emission,
            material,
            maps,
            maps_used,
            spacing_m,
            emission_scale,
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
        let TriangleValues {
            tris,
            emissions,
            materials,
            albedo_maps,
        } = attribute_triangles(
            &a.scene,
            t_s,
            self.maps_used,
            self.spacing_m,
            self.emission_scale,
        );
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
        if let Some(r) = &mut self.albedo_maps {
            r.write_slot(slot, a.capacity, &OwnerRows::maps(&albedo_maps[..n]));
        }
        if let Some(w) = &mut self.emission {
            let rows = OwnerRows::new(&emissions[..n], w.with_maps);
            w.values.write_slot(slot, a.capacity, &rows);
        }
        if let Some(w) = &mut self.material {
            let rows = OwnerRows::new(&materials[..n], w.with_maps);
            w.values.write_slot(slot, a.capacity, &rows);
        }
        a.counts[slot].store(n as u32, Ordering::SeqCst);
        a.splits[slot].store(attribute_splits(&a.grid, &tris[..n]), Ordering::SeqCst);
        a.last = Some(tris);
        true
    }

    /// Declares `voxelize_attributes`, (with emitters) `voxelize_emission`, (with a material
    /// volume) `voxelize_material` and `voxelize_attributes_resolve`, writing the voxels of this writer's triangles into the
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
        let maps = self.maps.as_ref().map(|m| m.import(g, read));
        for (writer, volume) in [(&self.emission, v.emission), (&self.material, v.material)] {
            if let (Some(w), Some(volume)) = (writer, volume) {
                w.add_pass(
                    g,
                    OwnerInputs {
                        owner,
                        volume,
                        tris,
                        maps,
                        push: self.push,
                    },
                    self.animated.as_ref(),
                    &self.gate,
                    extent,
                );
            }
        }
        let resolve = *self.resolve_pipeline;
        // Without albedo maps the shader reads neither them nor the map buffers (a
        // specialization constant): the triangles stand in.
        let albedo_maps = self
            .albedo_maps
            .as_ref()
            .map(|r| r.import(g, self.animated.as_ref()));
        let (rows, texels, table) = match (albedo_maps, maps) {
            (Some(rows), Some((texels, table))) => (rows, texels, table),
            _ => (tris, tris, tris),
        };
        let rpush = self.push;
        g.add_pass("voxelize_attributes_resolve")
            .pipeline(&resolve)
            .bind(0, tris, read)
            .bind(1, owner, rw)
            .bind(2, albedo, rw)
            .bind(3, normal, rw)
            .bind(4, rows, read)
            .bind(5, texels, read)
            .bind(6, table, read)
            .when(Some(self.gate.clone()))
            .record(move |ctx| {
                ctx.bind(&resolve);
                ctx.cmd.push_constants(&resolve, bytemuck::bytes_of(&rpush));
                ctx.cmd
                    .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), extent.2);
            });
    }
}

impl OwnerValueWriter {
    /// Pass `name`'s pipeline (shader `name.comp`) and its values buffer: one region of
    /// `capacity` triangles per frame slot for scenes with moving objects (`capacity` Some),
    /// else just `values`.
    fn new(
        ctx: &Context,
        name: &'static str,
        rows: OwnerRows,
        capacity: Option<usize>,
    ) -> Result<Self, VkError> {
        let with_maps = rows.stride > 1;
        let pipeline = ctx.compute_pipeline(
            &format!("{name}.comp"),
            crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            &crate::spec_constants![HAS_MAPS = with_maps],
        )?;
        let values = TriangleRows::new(ctx, &format!("{name} values"), &rows, capacity)?;
        Ok(Self {
            name,
            pipeline,
            values,
            with_maps,
        })
    }

    /// Declares the pass: every voxel of `extent` with an owner in `inp.owner` takes the
    /// owner's value in `inp.volume` (with maps: sampled over its part of the voxel), in the
    /// slots `gate` opens (each slot reads its own region of the values when `animated`).
    fn add_pass(
        &self,
        g: &mut RenderGraph,
        inp: OwnerInputs,
        animated: Option<&AnimatedTriangles>,
        gate: &Arc<SlotCondition>,
        extent: (u32, u32, u32),
    ) {
        let read = Access::StorageRead(Shader::Compute);
        let values = self.values.import(g, animated);
        // Without maps the shader reads neither the maps nor the triangles (a specialization
        // constant); the values stand in for the maps' bindings.
        let (texels, table) = match inp.maps {
            Some(m) if self.with_maps => m,
            _ => (values, values),
        };
        let (pipe, push) = (*self.pipeline, inp.push);
        g.add_pass(self.name)
            .pipeline(&pipe)
            .bind(0, values, read)
            .bind(1, inp.owner, read)
            .bind(2, inp.volume, Access::StorageReadWrite(Shader::Compute))
            .bind(3, inp.tris, read)
            .bind(4, texels, read)
            .bind(5, table, read)
            .when(Some(gate.clone()))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd
                    .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), extent.2);
            });
    }
}

impl TriangleRows {
    /// Uploads `rows`: once, or into each frame slot's region of `capacity` triangles for
    /// scenes with moving objects (`capacity` Some).
    fn new(
        ctx: &Context,
        name: &str,
        rows: &OwnerRows,
        capacity: Option<usize>,
    ) -> Result<Self, VkError> {
        let stride = rows.stride;
        let Some(capacity) = capacity else {
            let bytes: &[u8] = if rows.vec4s.is_empty() {
                &[0; 16]
            } else {
                bytemuck::cast_slice(&rows.vec4s)
            };
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let buffer = ctx.upload_buffer(name, bytes, usage)?;
            return Ok(Self { buffer, stride });
        };
        let buffer = ctx.create_buffer(&BufferDesc {
            name: format!("{name} (per frame slot)"),
            size_bytes: Self::region(capacity, stride) * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let mut me = Self { buffer, stride };
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            me.write_slot(slot, capacity, rows);
        }
        Ok(me)
    }

    /// Bytes of one frame slot's region of `capacity` triangles.
    fn region(capacity: usize, stride: usize) -> u64 {
        (capacity * stride * std::mem::size_of::<[f32; 4]>()) as u64
    }

    /// Writes frame slot `slot`'s region (of `capacity` triangles) of a per-slot buffer.
    fn write_slot(&mut self, slot: usize, capacity: usize, rows: &OwnerRows) {
        let region = Self::region(capacity, rows.stride) as usize;
        let n = rows.vec4s.len().min(capacity * rows.stride);
        if let Some(m) = self.buffer.mapped_mut() {
            let bytes: &[u8] = bytemuck::cast_slice(&rows.vec4s[..n]);
            m[slot * region..slot * region + bytes.len()].copy_from_slice(bytes);
        }
    }

    /// Imports the rows for a shader read: each frame slot its own region when `animated`.
    fn import(&self, g: &mut RenderGraph, animated: Option<&AnimatedTriangles>) -> BufferHandle {
        let read = Access::StorageRead(Shader::Compute);
        match animated {
            Some(a) => {
                let region = Self::region(a.capacity, self.stride);
                g.import_buffer_per_slot(&self.buffer, region, region, read)
            }
            None => g.import_buffer(&self.buffer, read),
        }
    }
}

/// A cleared `RGBA16F` volume congruent with `grid`, in [`ATTRIBUTE_VOLUME_STATE`].
fn value_volume(ctx: &Context, grid: &VoxelGrid, name: &str) -> Result<Image, VkError> {
    let ext = grid.extent_voxels();
    let desc = ImageDesc::new_2d(name, VALUE_FORMAT, ext.x, ext.y)
        .with_depth(ext.z)
        .with_usage(
            vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
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
            let [a, b, c] = [0, 1, 2].map(|k| Vec3::new(t[k][0], t[k][1], t[k][2]));
            voxelize_loads(grid, a.min(b).min(c), a.max(b).max(c))
        })
        .max()
        .unwrap_or(0);
    voxelize_splits(loads, ATTRIBUTE_GROUP_SIZE)
}

/// A triangle's value for one owner-value pass and the maps that replace it per texel.
type OwnerValue = ([f32; 4], GpuTriangleMaps);

/// What [`attribute_triangles`] gives per triangle, in the owner order.
struct TriangleValues {
    tris: Vec<AttributeTriangle>,
    emissions: Vec<OwnerValue>,
    materials: Vec<OwnerValue>,
    /// The maps the resolve pass samples (`map_Kd` in `maps[3]`).
    albedo_maps: Vec<GpuTriangleMaps>,
}

/// Every triangle of `scene` at `t_s` with its material's albedo, its material's emission and
/// its material's lobe ([`material_texel`]), each with the triangle's [`GpuTriangleMaps`] for
/// the maps `maps` samples (spaced `spacing_m`). The emission is `Ke` where `map_Ke` is
/// sampled per texel (the pass multiplies), else [`Material::voxel_emission`] (`Ke` × the
/// map's mean); the lobe holds the constants or means, which sampled maps replace; the
/// albedo is `Kd`, which a sampled `map_Kd` replaces. The emission is multiplied by
/// `emission_scale`, the pre-exposure of the half-float emission volume ([`PreExposure`]).
fn attribute_triangles(
    scene: &Scene,
    t_s: f32,
    maps: MapUse,
    spacing_m: f32,
    emission_scale: f32,
) -> TriangleValues {
    let mut out = Vec::new();
    let mut emissions = Vec::new();
    let mut materials = Vec::new();
    for object in &scene.objects {
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let m = object.transform_at(t_s);
        // The resolve pass takes the face normal from the winding: a mirroring transform
        // reads the corners reversed, so it stays on the side the normals point to.
        let order = crate::scene::corner_order(&m);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let opacity = scene
                .materials
                .get(material)
                .map_or(1.0, |m| m.coverage_opacity(&scene.textures));
            let [transparency, seed] = Coverage::new(&object.name, opacity).gpu_w();
            let (albedo, emission, lobe, map_ids) = scene.materials.get(material).map_or(
                (Vec3::splat(0.5), Vec3::ZERO, [0.0; 4], [-1; 4]),
                |m| {
                    let ids = maps.maps_of(m);
                    let emission = if ids[2] >= 0 {
                        m.emission
                    } else {
                        m.voxel_emission(&scene.textures)
                    };
                    let emission = emission * emission_scale;
                    (m.albedo, emission, material_texel(m, &scene.textures), ids)
                },
            );
            let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
            for t in mesh.indices[range].chunks_exact(3) {
                let p = order.map(|k| m.transform_point3(mesh.positions[t[k] as usize]));
                let [v0, v1, v2] = [0, 1, 2].map(|k| [p[k].x, p[k].y, p[k].z, albedo[k]]);
                out.push([v0, v1, v2, [transparency, seed, 0.0, 0.0]]);
                let row = if map_ids == [-1; 4] {
                    GpuTriangleMaps::NONE
                } else {
                    let uv = order.map(|k| {
                        mesh.uvs
                            .as_ref()
                            .and_then(|uvs| uvs.get(t[k] as usize).copied())
                            .unwrap_or(Vec2::ZERO)
                    });
                    GpuTriangleMaps::new(map_ids, p, uv, spacing_m)
                };
                emissions.push((emission.extend(0.0).to_array(), row));
                materials.push((lobe, row));
            }
        }
    }
    // Emitters own the voxels they share (smallest index wins): a light patch just under a
    // ceiling shares the ceiling's voxels, and must emit from them. A stable partition, so a
    // scene without emitters keeps its order.
    let mut all: Vec<_> = out
        .into_iter()
        .zip(emissions)
        .zip(materials)
        .map(|((t, e), m)| (t, e, m))
        .collect();
    all.sort_by_key(|(_, e, _)| e.0[..3] == [0.0; 3]);
    let mut v = TriangleValues {
        tris: Vec::with_capacity(all.len()),
        emissions: Vec::with_capacity(all.len()),
        materials: Vec::with_capacity(all.len()),
        albedo_maps: Vec::with_capacity(all.len()),
    };
    for (t, e, m) in all {
        v.tris.push(t);
        v.albedo_maps.push(e.1);
        v.emissions.push(e);
        v.materials.push(m);
    }
    v
}

/// Formats of the resolved volumes (what `gi_pathtrace.comp` samples).
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const NORMAL_FORMAT: vk::Format = vk::Format::R8G8B8A8_SNORM;

/// State of the resolved volumes between frames: sampled by compute shaders.
pub const VOLUME_STATE: Access = Access::Sampled(Shader::Compute);

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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::scene::{Ggx, TextureData};

    /// A 2×1 texture of two RGBA texels.
    fn two_texels(a: [u8; 3], b: [u8; 3], srgb: bool) -> TextureData {
        let rgba8 = [a, b]
            .iter()
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect();
        TextureData::new("two".into(), 2, 1, rgba8, srgb)
    }

    #[test]
    fn voxelizer_gets_the_pbr_maps_means_times_the_constants() {
        let text = "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                    [[objects]]\nbuiltin = \"cube\"\nmaterial = { roughness = 0.9, \
                    emission_w_sr_m2 = [2, 4, 6] }\n";
        let mut scene = Scene::from_toml_str(text, Path::new("t.toml"), Path::new(".")).unwrap();
        let none = MapUse::default();
        let plain = attribute_triangles(&scene, 0.0, none, 0.01, 1.0);
        // Without maps the voxelizer gets the constants.
        assert!(plain.emissions.iter().all(|e| e.0 == [2.0, 4.0, 6.0, 0.0]));
        assert!(plain.materials.iter().all(|m| m.0 == [0.9, 0.0, 0.0, -1.0]));
        assert!(plain.emissions.iter().all(|e| e.1 == GpuTriangleMaps::NONE));

        // Roughness texels 0 and 255 (linear): mean 0.5. Metalness 51 and 51: 0.2. Emission
        // sRGB texels 188 and 0: the mean of the decoded values, srgb_decode(188/255)/2 ≈
        // 0.252 (averaging the codes first would give srgb_decode(94/255) ≈ 0.112). An albedo
        // texture (sRGB) that only the per-texel volumes read: the means keep `Kd`.
        scene.textures = vec![
            two_texels([0; 3], [255; 3], false),
            two_texels([51; 3], [51; 3], false),
            two_texels([188; 3], [0; 3], true),
            two_texels([255, 0, 0], [0, 255, 0], true),
        ];
        let m = scene.objects[0].materials[0];
        scene.materials[m].pbr_maps = crate::scene::PbrMaps {
            roughness: Some(0),
            metallic: Some(1),
            emission: Some(2),
        };
        scene.materials[m].albedo_texture = Some(3);
        let kd = scene.materials[m].albedo;
        let TriangleValues {
            tris,
            emissions,
            materials,
            albedo_maps,
        } = attribute_triangles(&scene, 0.0, none, 0.01, 1.0);
        assert_eq!(tris.len(), plain.tris.len());
        assert!(tris
            .iter()
            .all(|t| [t[0][3], t[1][3], t[2][3]] == kd.to_array()));
        assert!(albedo_maps.iter().all(|r| *r == GpuTriangleMaps::NONE));
        let glow = crate::eval::srgb_decode(188.0 / 255.0) / 2.0;
        let want = Vec3::new(2.0, 4.0, 6.0) * glow;
        for (e, _) in &emissions {
            assert!(Vec3::from_slice(&e[..3]).abs_diff_eq(want, 1e-6), "{e:?}");
        }
        let ggx = scene.materials[m].voxel_ggx(&scene.textures).unwrap();
        assert!((ggx.roughness - 0.5).abs() < 1e-6 && (ggx.metallic - 0.2).abs() < 1e-6);
        let lobe = [ggx.roughness, ggx.metallic, 0.0, -1.0];
        assert!(materials.iter().all(|l| l.0 == lobe));
        // Per texel: the emission pass gets Ke (it multiplies by the sampled map) and every
        // triangle its maps; the lobe keeps the means, which the samples replace.
        let texel = MapUse {
            emission: true,
            lobe: true,
            albedo: true,
        };
        assert_eq!(MapUse::new(&scene, true, true, true), texel);
        let v = attribute_triangles(&scene, 0.0, texel, 0.01, 1.0);
        assert!(v
            .emissions
            .iter()
            .all(|(e, r)| *e == [2.0, 4.0, 6.0, 0.0] && r.maps == [0, 1, 2, 3]));
        assert!(v
            .materials
            .iter()
            .all(|(l, r)| *l == lobe && r.maps == [0, 1, 2, 3]));
        // The resolve pass reads the albedo map (`Kd` stays in the triangles, unused there).
        assert!(v.albedo_maps.iter().all(|r| r.maps[3] == 3));
        // The G-buffer keeps the constants next to the maps (it samples the maps).
        assert_eq!(
            scene.materials[m].ggx,
            Some(Ggx {
                roughness: 0.9,
                metallic: 0.0
            })
        );
    }
}

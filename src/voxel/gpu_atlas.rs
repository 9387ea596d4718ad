//! The thesis's atlas voxelizer on the GPU (Thiedemann 2010, §4.2.2–§4.3.1)
//! with the automatic atlases of [`super::atlas`].
//!
//! # Passes (named after their GLSL stems)
//! - `atlas_positions` (graphics, once per atlas): each triangle's atlas cell is drawn as a
//!   quad with the atlas position as clip position; the fragment shader writes the
//!   **model-space** position of the closest triangle point for the texels the triangle owns
//!   (conservative: thin and tiny triangles keep at least one texel).
//! - `atlas_points` (compute, once per atlas): compacts the valid texels into a point list
//!   (Thiedemann 2010, §4.3.1 step 2). Rigid objects therefore pay the rasterization once; per
//!   frame only their points are transformed, so the cost follows the atlas size (the surface area
//!   over the voxel size), not the triangle count.
//! - `voxelize_atlas` (compute, per voxelization): one invocation per point transforms it by
//!   the object's model matrix and ORs its single bit into the **column buffer** with
//!   `atomicOr`. The thesis ORs a single-bit LUT into an `RGBA32UI` target with `logicOp OR`;
//!   the buffer is chosen here because the triangle voxelizer already writes it, so both
//!   voxelizers share `voxel_clear` / `voxel_copy_static` (static grid + dynamic objects),
//!   `voxel_store` and the mip chain, and can be mixed in one frame.
//!
//! # OBJ sequences
//! A sequence whose frames share topology gets one atlas for all frames
//! ([`super::atlas::build_sequence_atlas`], hole-free in every frame). Its position atlas
//! is rendered once per frame with that frame's vertices through the shared layout, giving
//! one point list per frame, built once at load (the thesis re-rasterizes animated objects'
//! atlases every frame, §4.2.2; here a frame change only picks another list). Per
//! frame slot the instance splats the list of the frame `Object::mesh_at` selects
//! ([`SlotFrames`], next to the model matrix of [`SlotMatrices`]). The alternative, one list
//! of (triangle, barycentric) points and per-frame vertex buffers, would keep memory at one
//! list, but changes every splatting shader; per-frame lists cost frames × points × 16 bytes.
//! A sequence whose frames differ in topology keeps the triangle voxelizer (logged).
//!
//! Every sample lies on its triangle, so the atlas voxels are a subset of the conservative
//! triangle voxelization ([`super::voxelize`]) up to f32 rounding at voxel boundaries.
//!
//! # Opacity
//! A surface of opacity below 1 is held as the triangle voxelizer holds it, by stochastic
//! coverage ([`super::coverage`]): a point sets its voxel where `coverage_covers` of
//! `voxel_coverage.glsl` keeps it. A point carries only its triangle's index, and one object
//! may have several materials, so an instance whose object has such a surface gets a
//! per-triangle coverage buffer ([`AtlasCoverage`]) that all three passes placing points
//! bind (`voxelize_atlas`, `voxelize_atlas_bits`, `voxelize_atlas_volumes`); the push
//! constants' `extent.w` says whether it is bound. Opaque instances bind their point chunk in
//! its place and take no decision, so opaque scenes voxelize bit for bit as before.

use super::atlas::{AtlasCache, MeshAtlas};
use super::coverage::{object_coverage, Coverage};
use super::gpu::{image_extent, GpuVoxelError, SlotGate};
use super::VoxelGrid;
use crate::graph::{run_once, Access, BufferHandle, ImageHandle, Load, RenderGraph, Shader};
use crate::scene::{Animation, Scene};
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, GraphicsPipeline, GraphicsPipelineDesc,
    ImageDesc, MemoryLocation, PassTiming, VkError, MAX_FRAMES_IN_FLIGHT,
};
use glam::{Mat4, Vec3};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Format of the position atlas (model-space xyz, w = 1 where a triangle owns the texel).
pub const ATLAS_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The position atlas's w holds the triangle index + 1 as an f32, exact below 2^24.
const ATLAS_MAX_TRIANGLES: usize = 1 << 24;

/// Points per row of `voxelize_atlas` workgroups past which the dispatch gets a second
/// dimension (65535 groups of 64).
const MAX_POINTS_X: u32 = 65535 * 64;

/// One atlas triangle as the shaders read it (`struct AtlasTriangle`, atlas_triangle.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAtlasTriangle {
    pub p: [[f32; 4]; 3],
    pub uv01: [f32; 4],
    pub uv2: [f32; 4],
    pub cell: [u32; 4],
}

/// Push constants of `atlas_positions.vert`: the atlas size in texels (xy).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuAtlasPositionsPush {
    atlas_size: [f32; 4],
}

crate::push_constants!(GpuAtlasPositionsPush { atlas_size });

/// Push constants of `atlas_points.comp`: the band of atlas rows one dispatch converts.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuAtlasPointsPush {
    row0: u32,
    rows: u32,
    _pad: [u32; 2],
}

crate::push_constants!(GpuAtlasPointsPush { row0, rows, _pad });

/// Push constants of `voxelize_atlas.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAtlasVoxelizePush {
    pub model: [f32; 16],
    pub grid_min: [f32; 4],
    pub scale: [f32; 4],
    pub dims: [u32; 4],
    pub extent: [u32; 4],
}

crate::push_constants!(GpuAtlasVoxelizePush {
    model,
    grid_min,
    scale,
    dims,
    extent
});

impl GpuAtlasVoxelizePush {
    /// `count` points placed by `model` into `grid`, whose column target is `columns_px`
    /// (width, height; unused by the passes that write images).
    pub fn new(grid: &VoxelGrid, model: Mat4, columns_px: (u32, u32), count: u32) -> Self {
        let ext = grid.extent_voxels();
        Self {
            model: model.to_cols_array(),
            grid_min: grid.world_min().extend(0.0).to_array(),
            scale: grid.voxels_per_meter().extend(0.0).to_array(),
            dims: [ext.x, ext.y, ext.z, grid.axis().index() as u32],
            extent: [columns_px.0, columns_px.1, count, 0],
        }
    }

    /// This push with `extent.w` telling the shader whether the draw's coverage buffer is
    /// bound (`atlas_point_covers` of `voxel_coverage.glsl`).
    pub fn with_coverage(mut self, bound: bool) -> Self {
        self.extent[3] = u32::from(bound);
        self
    }
}

/// Binding of the per-triangle coverage in `voxelize_atlas.comp` and
/// `voxelize_atlas_bits.vert` (`ATLAS_COVERAGE_BINDING`).
pub const COVERAGE_BINDING: u32 = 2;

/// One object's per-triangle coverage (`vec2(1 − opacity, seed)` per triangle, indexed by
/// the points' triangle index) for the atlas passes, uploaded only where some triangle has
/// opacity below 1.
pub struct AtlasCoverage {
    pub buffer: Buffer,
}

impl AtlasCoverage {
    /// The coverage of `object`'s triangles drawn from `mesh`; `None` when all are opaque
    /// (no buffer, no decision).
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        object: &crate::scene::Object,
        mesh: usize,
    ) -> Result<Option<Self>, VkError> {
        let coverage = object_coverage(scene, object, mesh);
        if coverage.iter().all(Coverage::is_opaque) {
            return Ok(None);
        }
        let rows: Vec<[f32; 2]> = coverage.iter().map(Coverage::gpu_w).collect();
        let buffer = ctx.upload_buffer(
            &format!("atlas coverage ({})", object.name),
            bytemuck::cast_slice(&rows),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Some(Self { buffer }))
    }
}

/// The pipelines of the atlas passes.
pub struct AtlasPipelines {
    positions: GraphicsPipeline,
    points: ComputePipeline,
    voxelize: ComputePipeline,
    sampler: crate::vk::Sampler,
}

impl AtlasPipelines {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let mut desc = GraphicsPipelineDesc::fullscreen(
            "atlas_positions.vert",
            "atlas_positions.frag",
            ATLAS_FORMAT,
        );
        desc.push = crate::vk::PushLayout::of::<GpuAtlasPositionsPush>();
        let positions = ctx.graphics_pipeline(&desc)?;
        let points = ctx.compute_pipeline(
            "atlas_points.comp",
            crate::vk::PushLayout::of::<GpuAtlasPointsPush>(),
            &[],
        )?;
        let voxelize = ctx.compute_pipeline(
            "voxelize_atlas.comp",
            crate::vk::PushLayout::of::<GpuAtlasVoxelizePush>(),
            &[],
        )?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        Ok(Self {
            positions,
            points,
            voxelize,
            sampler,
        })
    }
}

/// One chunk of a point list: its own buffer, at most the device's storage-buffer range.
pub struct PointChunk {
    pub buffer: Buffer,
    pub count: u32,
}

/// The valid texels of one atlas in device buffers: `uvec4` per point, the model-space
/// position's f32 bits and the index of the triangle it lies on (`atlas_points.comp`).
///
/// A shader binding can address at most `maxStorageBufferRange` bytes (128 MiB, 8.4 M
/// points, on lavapipe; the dense-bunnies scene has 14.6 M at 512², and the compaction's
/// room for every texel passes 128 MiB already at Cornell 512²), so the list is split into
/// chunks of at most that many bytes, each its own buffer, and every consumer dispatches or draws per chunk.
/// Separate buffers rather than one buffer bound at per-chunk offsets: no chunk's size has
/// to respect `minStorageBufferOffsetAlignment`, and no single allocation has to hold the
/// whole list (`maxMemoryAllocationSize`).
pub struct AtlasPoints {
    /// The sorted list in order, each chunk full but the last; empty when there are no
    /// points.
    pub chunks: Vec<PointChunk>,
    /// Points in all chunks.
    pub count: u64,
    /// The atlas's `(width, height)` in texels.
    pub atlas_extent: (u32, u32),
    /// GPU times of the one-time passes that built the point list (`voxgi profile` lists
    /// them apart from the frame's).
    pub setup_timings: Vec<PassTiming>,
}

impl AtlasPoints {}

/// The bytes one point-list chunk may hold on `ctx`'s device: its storage-buffer range,
/// whole points only.
pub fn device_chunk_bytes(ctx: &Context) -> u64 {
    u64::from(ctx.info.max_storage_buffer_range) / POINT_BYTES * POINT_BYTES
}

/// Bytes per point (`uvec4`).
const POINT_BYTES: u64 = 16;

/// Bytes of `atlas_points`'s count header (one `uint` padded to a `uvec4`).
const SCRATCH_HEADER_BYTES: u64 = 16;

/// The atlas row bands `[first row, row count)` that `atlas_points` compacts each into its
/// own scratch buffer: a band's scratch (header + room for every texel) fits `chunk_bytes`.
/// `None` when not even one row fits.
fn scratch_bands(w: u32, h: u32, chunk_bytes: u64) -> Option<Vec<(u32, u32)>> {
    let row_bytes = u64::from(w) * POINT_BYTES;
    let rows = chunk_bytes.checked_sub(SCRATCH_HEADER_BYTES)? / row_bytes.max(1);
    let rows = u32::try_from(rows).unwrap_or(u32::MAX).min(h.max(1));
    if rows == 0 {
        return None;
    }
    Some(
        (0..h)
            .step_by(rows as usize)
            .map(|y| (y, rows.min(h - y)))
            .collect(),
    )
}

/// The triangles of `atlas` as `atlas_positions` reads them (model-space vertices).
pub fn gpu_atlas_triangles(
    atlas: &MeshAtlas,
    positions: &[Vec3],
    indices: &[u32],
) -> Vec<GpuAtlasTriangle> {
    atlas
        .triangles
        .iter()
        .zip(indices.chunks_exact(3))
        .map(|(t, idx)| GpuAtlasTriangle {
            p: [0, 1, 2].map(|k| {
                positions
                    .get(idx[k] as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO)
                    .extend(1.0)
                    .to_array()
            }),
            uv01: [t.uv[0].x, t.uv[0].y, t.uv[1].x, t.uv[1].y],
            uv2: [t.uv[2].x, t.uv[2].y, 0.0, 0.0],
            cell: t.cell,
        })
        .collect()
}

/// Declares `atlas_positions`: renders the `count` atlas triangles of `triangles` into a new
/// `extent` position atlas ([`ATLAS_FORMAT`], invalid texels cleared to 0), returned.
pub fn add_atlas_positions_pass(
    g: &mut RenderGraph,
    pipes: &AtlasPipelines,
    triangles: BufferHandle,
    count: u32,
    (w, h): (u32, u32),
) -> ImageHandle {
    let image = g.create_image(ImageDesc::new_2d("position atlas", ATLAS_FORMAT, w, h));
    let (pipe, size) = (*pipes.positions, [w as f32, h as f32, 0.0, 0.0]);
    g.add_pass("atlas_positions")
        .pipeline(&pipe)
        .bind(0, triangles, Access::StorageRead(Shader::Graphics))
        .color(image, Load::Clear([0.0; 4]))
        .record(move |ctx| {
            ctx.begin_rendering();
            ctx.bind(&pipe);
            ctx.cmd.push_constants(
                &pipe,
                bytemuck::bytes_of(&GpuAtlasPositionsPush { atlas_size: size }),
            );
            ctx.cmd.draw(6 * count, 1);
            ctx.cmd.end_rendering();
        });
    image
}

/// Renders the position atlas of a mesh (`atlas_positions`) and compacts its valid texels
/// (`atlas_points`), once, into chunks of at most the device's storage-buffer range.
pub fn render_atlas_points(
    ctx: &Context,
    pipes: &AtlasPipelines,
    atlas: &MeshAtlas,
    positions: &[Vec3],
    indices: &[u32],
) -> Result<AtlasPoints, GpuVoxelError> {
    let chunk_bytes = device_chunk_bytes(ctx);
    render_atlas_points_chunked(ctx, pipes, atlas, positions, indices, chunk_bytes)
}

/// [`render_atlas_points`] with chunks (and `atlas_points` scratch bands) of at most
/// `chunk_bytes` (at most [`device_chunk_bytes`]; smaller to test the chunking).
///
/// `atlas_points` appends with an atomic counter, so it cannot know in which chunk a point
/// ends up. Instead each band of atlas rows is compacted into its own scratch buffer with
/// room for all its texels (so a band's scratch fits one binding), and the host, which
/// reads the points back anyway to sort them, splits the sorted list into full chunks.
pub fn render_atlas_points_chunked(
    ctx: &Context,
    pipes: &AtlasPipelines,
    atlas: &MeshAtlas,
    positions: &[Vec3],
    indices: &[u32],
    chunk_bytes: u64,
) -> Result<AtlasPoints, GpuVoxelError> {
    let tris = gpu_atlas_triangles(atlas, positions, indices);
    if tris.len() >= ATLAS_MAX_TRIANGLES {
        return Err(GpuVoxelError::TooManyAtlasTriangles {
            mesh_triangles: tris.len(),
            max: ATLAS_MAX_TRIANGLES,
        });
    }
    let (w, h) = (atlas.width, atlas.height);
    let chunk_bytes = chunk_bytes.min(device_chunk_bytes(ctx)) / POINT_BYTES * POINT_BYTES;
    let Some(bands) = scratch_bands(w, h, chunk_bytes) else {
        return Err(GpuVoxelError::AtlasRowTooLarge {
            width: w,
            bytes: SCRATCH_HEADER_BYTES + u64::from(w) * POINT_BYTES,
            max: chunk_bytes,
        });
    };
    let tri_buffer = ctx.upload_buffer(
        "atlas triangles",
        bytemuck::cast_slice(&tris),
        vk::BufferUsageFlags::STORAGE_BUFFER,
    )?;
    let mut scratch = Vec::with_capacity(bands.len());
    for (i, &(_, rows)) in bands.iter().enumerate() {
        scratch.push(ctx.create_buffer(&BufferDesc {
            name: format!("atlas points (scratch band {i})"),
            size_bytes: SCRATCH_HEADER_BYTES + u64::from(w) * u64::from(rows) * POINT_BYTES,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?);
    }
    let mut g = RenderGraph::new();
    let tri_h = g.import_buffer(&tri_buffer, Access::StorageRead(Shader::Graphics));
    let outs: Vec<(BufferHandle, u32, u32)> = scratch
        .iter()
        .zip(&bands)
        .map(|(b, &(row0, rows))| (g.import_buffer(b, Access::HostRead), row0, rows))
        .collect();
    let image = add_atlas_positions_pass(&mut g, pipes, tri_h, tris.len() as u32, (w, h));
    let mut clear = g.add_pass("atlas_points_clear");
    for &(out, _, _) in &outs {
        clear = clear.write(out, Access::TransferWrite);
    }
    let cleared = outs.clone();
    clear.record(move |ctx| {
        for &(out, _, _) in &cleared {
            ctx.cmd.fill_buffer(ctx.buffer(out).raw, 0);
        }
    });
    let (pipe, sampler) = (*pipes.points, pipes.sampler.raw);
    let bands_h = outs.clone();
    g.add_pass("atlas_points")
        .pipeline(&pipe)
        .bind_sampled(0, image, sampler, Shader::Compute)
        .bind_one_of(
            1,
            outs.iter().map(|o| o.0),
            Access::StorageReadWrite(Shader::Compute),
        )
        .record(move |ctx| {
            for &(out, row0, rows) in &bands_h {
                ctx.bind_with(&pipe, &[(1, out)]);
                ctx.cmd.push_constants(
                    &pipe,
                    bytemuck::bytes_of(&GpuAtlasPointsPush {
                        row0,
                        rows,
                        _pad: [0; 2],
                    }),
                );
                ctx.cmd.dispatch(w.div_ceil(8), rows.div_ceil(8), 1);
            }
        });
    for &(out, _, _) in &outs {
        g.mark_output(out);
    }
    let setup_timings = run_once(ctx, g)?;
    let mut points: Vec<[u32; 4]> = Vec::new();
    for (b, &(_, rows)) in scratch.iter().zip(&bands) {
        let bytes = b.mapped().unwrap_or(&[]);
        let count = bytes
            .get(..4)
            .map_or(0, |b| u32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
            .min(w.saturating_mul(rows));
        let first = SCRATCH_HEADER_BYTES as usize;
        let raw = bytes
            .get(first..first + count as usize * POINT_BYTES as usize)
            .unwrap_or(&[]);
        points.extend(
            raw.chunks_exact(POINT_BYTES as usize)
                .map(bytemuck::pod_read_unaligned::<[u32; 4]>),
        );
    }
    // `atlas_points` appends in whatever order its atomics ran. Sorted, the list has one
    // order per atlas (whatever the bands), so `voxelize_atlas_volumes`, whose additive
    // blending sums in primitive order (across the chunks' draws too), gives the same
    // f16 sums (hence volumes) every time it is built.
    points.sort_unstable_by_key(|p| (p[3], p[0], p[1], p[2]));
    let per_chunk = (chunk_bytes / POINT_BYTES).max(1) as usize;
    let mut chunks = Vec::with_capacity(points.len().div_ceil(per_chunk));
    for (i, c) in points.chunks(per_chunk).enumerate() {
        let buffer = ctx.upload_buffer(
            &format!("atlas points (chunk {i})"),
            bytemuck::cast_slice(c),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        chunks.push(PointChunk {
            buffer,
            count: c.len() as u32,
        });
    }
    Ok(AtlasPoints {
        chunks,
        count: points.len() as u64,
        atlas_extent: (w, h),
        setup_timings,
    })
}

/// A model matrix per frame slot, written by the host after the slot's fence.
#[derive(Debug, Default)]
pub struct SlotMatrices {
    models: [Mutex<Mat4>; MAX_FRAMES_IN_FLIGHT],
}

impl SlotMatrices {
    pub fn set(&self, slot: usize, m: Mat4) {
        if let Some(Ok(mut g)) = self.models.get(slot).map(|m| m.lock()) {
            *g = m;
        }
    }

    fn get(&self, slot: usize) -> Mat4 {
        self.models
            .get(slot)
            .and_then(|m| m.lock().ok().map(|g| *g))
            .unwrap_or(Mat4::IDENTITY)
    }
}

/// Where a `voxelize_atlas` instance takes its model matrix from.
#[derive(Clone, Debug)]
pub enum ModelAt {
    Fixed(Mat4),
    PerSlot(Arc<SlotMatrices>),
}

impl ModelAt {
    /// The model matrix of frame slot `slot`.
    pub fn at(&self, slot: usize) -> Mat4 {
        match self {
            ModelAt::Fixed(m) => *m,
            ModelAt::PerSlot(s) => s.get(slot),
        }
    }
}

/// A sequence frame index per frame slot, written by the host after the slot's fence: which
/// of an OBJ sequence's point lists the slot splats.
#[derive(Debug, Default)]
pub struct SlotFrames {
    frames: [AtomicUsize; MAX_FRAMES_IN_FLIGHT],
}

impl SlotFrames {
    pub fn set(&self, slot: usize, frame: usize) {
        if let Some(f) = self.frames.get(slot) {
            f.store(frame, Ordering::SeqCst);
        }
    }

    fn get(&self, slot: usize) -> usize {
        self.frames
            .get(slot)
            .map_or(0, |f| f.load(Ordering::SeqCst))
    }
}

/// Which of an instance's point lists a slot splats.
#[derive(Clone, Debug)]
pub enum FrameAt {
    Fixed(usize),
    PerSlot(Arc<SlotFrames>),
}

impl FrameAt {
    pub fn at(&self, slot: usize) -> usize {
        match self {
            FrameAt::Fixed(f) => *f,
            FrameAt::PerSlot(s) => s.get(slot),
        }
    }
}

/// One object's atlas points for a splatting pass: one list per sequence frame (one for
/// rigid objects), the frame and the model matrix per slot.
#[derive(Clone)]
pub struct AtlasInstance<'a> {
    pub frames: Vec<&'a AtlasPoints>,
    /// Per frame, the triangles' coverage where some has opacity below 1.
    pub coverage: Vec<Option<&'a AtlasCoverage>>,
    pub frame: FrameAt,
    pub model: ModelAt,
}

/// An [`AtlasInstance`] imported into a graph: every frame's chunks `(points, count)`.
#[derive(Clone)]
pub struct ImportedInstance {
    pub frames: Vec<Vec<(BufferHandle, u32)>>,
    /// Per frame, the imported coverage buffer (none for an opaque object).
    pub coverage: Vec<Option<BufferHandle>>,
    pub frame: FrameAt,
    pub model: ModelAt,
}

impl<'a> AtlasInstance<'a> {
    /// A rigid object's one point list at a fixed model matrix.
    pub fn rigid(points: &'a AtlasPoints, model: Mat4) -> Self {
        Self {
            frames: vec![points],
            coverage: vec![None],
            frame: FrameAt::Fixed(0),
            model: ModelAt::Fixed(model),
        }
    }

    /// Imports every chunk of every frame's points (all are declared read: the slot picks
    /// one frame at record time); `None` when no frame has points.
    pub fn import(&self, g: &mut RenderGraph, access: Access) -> Option<ImportedInstance> {
        if self.frames.iter().all(|p| p.count == 0) {
            return None;
        }
        Some(ImportedInstance {
            frames: self
                .frames
                .iter()
                .map(|p| import_chunks(g, p, access))
                .collect(),
            coverage: self
                .coverage
                .iter()
                .map(|c| c.map(|c| g.import_buffer(&c.buffer, access)))
                .collect(),
            frame: self.frame.clone(),
            model: self.model.clone(),
        })
    }
}

/// Imports every chunk of `points`: `(buffer, count)` each, in list order.
pub fn import_chunks(
    g: &mut RenderGraph,
    points: &AtlasPoints,
    access: Access,
) -> Vec<(BufferHandle, u32)> {
    points
        .chunks
        .iter()
        .map(|c| (g.import_buffer(&c.buffer, access), c.count))
        .collect()
}

impl ImportedInstance {
    /// The chunks `(points, count)` that slot `slot` splats (none: nothing), its model and
    /// its frame's coverage buffer (none for an opaque object).
    pub fn at(&self, slot: usize) -> (&[(BufferHandle, u32)], Mat4, Option<BufferHandle>) {
        let f = self.frame.at(slot).min(self.frames.len().saturating_sub(1));
        let chunks = self.frames.get(f).map_or(&[][..], Vec::as_slice);
        let coverage = self.coverage.get(f).copied().flatten();
        (chunks, self.model.at(slot), coverage)
    }

    pub fn handles(&self) -> impl Iterator<Item = BufferHandle> + '_ {
        self.frames.iter().flatten().map(|&(h, _)| h)
    }

    /// What the coverage binding may hold: the coverage buffers and, for opaque objects'
    /// draws (which never read it), the point chunks.
    pub fn coverage_handles(&self) -> impl Iterator<Item = BufferHandle> + '_ {
        self.handles()
            .chain(self.coverage.iter().flatten().copied())
    }
}

/// Declares `voxelize_atlas`: each instance ORs its slot's transformed points into
/// `columns` (which `voxel_clear` or `voxel_copy_static` initialised), one dispatch per
/// chunk. Records only in slots `gate` leaves open.
pub fn add_voxelize_atlas_pass(
    g: &mut RenderGraph,
    pipes: &AtlasPipelines,
    grid: &VoxelGrid,
    columns: BufferHandle,
    instances: &[AtlasInstance],
    gate: Option<Arc<SlotGate>>,
) {
    let read = Access::StorageRead(Shader::Compute);
    let sets: Vec<ImportedInstance> = instances.iter().filter_map(|i| i.import(g, read)).collect();
    if sets.is_empty() {
        return;
    }
    let (pipe, grid) = (*pipes.voxelize, *grid);
    let (w, h) = image_extent(&grid);
    let chunks: Vec<BufferHandle> = sets.iter().flat_map(ImportedInstance::handles).collect();
    let coverage: Vec<BufferHandle> = sets
        .iter()
        .flat_map(ImportedInstance::coverage_handles)
        .collect();
    g.add_pass("voxelize_atlas")
        .pipeline(&pipe)
        .bind_one_of(0, chunks, read)
        .bind(1, columns, Access::StorageReadWrite(Shader::Compute))
        .bind_one_of(COVERAGE_BINDING, coverage, read)
        .when(gate)
        .record(move |ctx| {
            for inst in &sets {
                let (chunks, model, coverage) = inst.at(ctx.slot);
                for &(buf, count) in chunks {
                    if count == 0 {
                        continue;
                    }
                    let push = GpuAtlasVoxelizePush::new(&grid, model, (w, h), count)
                        .with_coverage(coverage.is_some());
                    let cov = coverage.unwrap_or(buf);
                    ctx.bind_with(&pipe, &[(0, buf), (COVERAGE_BINDING, cov)]);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    let x = count.min(MAX_POINTS_X);
                    ctx.cmd.dispatch(x.div_ceil(64), count.div_ceil(x), 1);
                }
            }
        });
}

/// Whether the atlas voxelizer handles `object` when atlases are selected: everything but
/// OBJ sequences whose frames differ in topology ([`atlas_frames`]).
pub fn uses_atlas(scene: &Scene, object: &crate::scene::Object) -> bool {
    atlas_frames(scene, object).is_ok()
}

/// The meshes (indices into `scene.meshes`) that share `object`'s atlas, one per sequence
/// frame (just the mesh for other objects), or why they cannot share one: one atlas lays
/// out the triangles of an index buffer, so every frame needs the same indices and vertex
/// count (scene loading checks this for OBJ files; scenes built in code may not).
pub fn atlas_frames(scene: &Scene, object: &crate::scene::Object) -> Result<Vec<usize>, String> {
    let meshes = match &object.animation {
        Some(Animation::ObjSequence { meshes, .. }) if !meshes.is_empty() => meshes.clone(),
        _ => vec![object.mesh],
    };
    let mesh = |m: usize| {
        scene
            .meshes
            .get(m)
            .ok_or_else(|| format!("mesh {m} of object '{}' is missing", object.name))
    };
    let first = mesh(meshes[0])?;
    for (f, &m) in meshes.iter().enumerate().skip(1) {
        let other = mesh(m)?;
        if other.indices != first.indices || other.positions.len() != first.positions.len() {
            return Err(format!(
                "frame {f} ('{}') differs in topology from frame 0 ('{}': {} vertices, {} \
                 triangles vs {} and {}), so no atlas fits both",
                other.name,
                first.name,
                other.positions.len(),
                other.indices.len() / 3,
                first.positions.len(),
                first.indices.len() / 3,
            ));
        }
    }
    Ok(meshes)
}

/// A dynamic (moving, animated or sequence) object's atlas instance.
pub(super) struct DynamicInstance {
    /// Per sequence frame: `(mesh in the scene, its point list in AtlasScene::points)`.
    pub(super) frames: Vec<(usize, usize)>,
    /// Per sequence frame, its triangles' coverage (none where all are opaque).
    pub(super) coverage: Vec<Option<AtlasCoverage>>,
    pub(super) object: crate::scene::Object,
    pub(super) models: Arc<SlotMatrices>,
    pub(super) frame: Arc<SlotFrames>,
    /// Index of the object in the scene.
    pub(super) object_index: usize,
}

impl DynamicInstance {
    /// The sequence frame (index into `frames`) drawn at `t_s`.
    fn frame_at(&self, t_s: f32) -> usize {
        let mesh = self.object.mesh_at(t_s);
        self.frames
            .iter()
            .position(|&(m, _)| m == mesh)
            .unwrap_or(0)
    }
}

/// What the dynamic atlas objects show at a time: model matrix and sequence frame each.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasPose {
    pub models: Vec<Mat4>,
    pub frames: Vec<usize>,
}

/// The atlas side of a scene's voxelization: one point list per distinct (mesh, scale),
/// instanced by the objects with their model matrices.
pub struct AtlasScene {
    pub pipelines: AtlasPipelines,
    pub(super) points: Vec<AtlasPoints>,
    /// `(points, model, index of the object in the scene)`.
    pub(super) static_instances: Vec<(usize, Mat4, usize)>,
    /// Per static instance, its triangles' coverage (none where all are opaque).
    static_coverage: Vec<Option<AtlasCoverage>>,
    pub(super) dynamic_instances: Vec<DynamicInstance>,
}

impl AtlasScene {
    /// Builds (or takes from `cache`) the atlas of every object that [`uses_atlas`] (one per
    /// OBJ sequence), renders and compacts each (each frame's) once. Texels are sized for
    /// `grid`'s smallest voxel edge.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        grid: &VoxelGrid,
        cache: &mut AtlasCache,
    ) -> Result<Self, GpuVoxelError> {
        Self::new_chunked(ctx, scene, t_s, grid, cache, device_chunk_bytes(ctx))
    }

    /// [`Self::new`] with point-list chunks of at most `chunk_bytes` (see
    /// [`render_atlas_points_chunked`]).
    pub fn new_chunked(
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        grid: &VoxelGrid,
        cache: &mut AtlasCache,
        chunk_bytes: u64,
    ) -> Result<Self, GpuVoxelError> {
        let texel_m = super::atlas::texel_size_for_voxel(grid.voxel_size_m().min_element());
        let mut me = Self {
            pipelines: AtlasPipelines::new(ctx)?,
            points: Vec::new(),
            static_instances: Vec::new(),
            static_coverage: Vec::new(),
            dynamic_instances: Vec::new(),
        };
        // `(atlas, sequence frame, index into points)`: objects sharing a mesh (sequence)
        // and scale share its point lists.
        let mut built: Vec<(Arc<MeshAtlas>, usize, usize)> = Vec::new();
        let r = (|| -> Result<(), GpuVoxelError> {
            for (oi, o) in scene.objects.iter().enumerate() {
                let meshes = match atlas_frames(scene, o) {
                    Ok(m) => m,
                    Err(reason) => {
                        log::info!("object '{}' keeps the triangle voxelizer: {reason}", o.name);
                        continue;
                    }
                };
                let frames: Vec<&crate::scene::Mesh> =
                    meshes.iter().filter_map(|&m| scene.meshes.get(m)).collect();
                let Some(mesh) = frames.first() else {
                    continue;
                };
                let scale = o.transform_components_at(t_s).scale;
                let positions: Vec<&[Vec3]> =
                    frames.iter().map(|m| m.positions.as_slice()).collect();
                let atlas =
                    cache.get_sequence(&mesh.name, &positions, &mesh.indices, scale, texel_m)?;
                let mut lists = Vec::with_capacity(frames.len());
                for (f, m) in frames.iter().enumerate() {
                    let found = built
                        .iter()
                        .find(|(k, kf, _)| Arc::ptr_eq(k, &atlas) && *kf == f);
                    let pi = match found {
                        Some(&(_, _, i)) => i,
                        None => {
                            let p = render_atlas_points_chunked(
                                ctx,
                                &me.pipelines,
                                &atlas,
                                &m.positions,
                                &m.indices,
                                chunk_bytes,
                            )?;
                            me.points.push(p);
                            built.push((atlas.clone(), f, me.points.len() - 1));
                            me.points.len() - 1
                        }
                    };
                    lists.push((meshes[f], pi));
                }
                let mut coverage = Vec::with_capacity(lists.len());
                for &(m, _) in &lists {
                    coverage.push(AtlasCoverage::new(ctx, scene, o, m)?);
                }
                if o.dynamic || o.is_animated() {
                    let inst = DynamicInstance {
                        frames: lists,
                        coverage,
                        object: o.clone(),
                        models: Arc::new(SlotMatrices::default()),
                        frame: Arc::new(SlotFrames::default()),
                        object_index: oi,
                    };
                    let f = inst.frame_at(t_s);
                    for s in 0..MAX_FRAMES_IN_FLIGHT {
                        inst.models.set(s, o.transform_at(t_s));
                        inst.frame.set(s, f);
                    }
                    me.dynamic_instances.push(inst);
                } else {
                    me.static_instances
                        .push((lists[0].1, o.transform_at(t_s), oi));
                    me.static_coverage
                        .push(coverage.into_iter().next().flatten());
                }
            }
            Ok(())
        })();
        r?;
        Ok(me)
    }

    pub fn has_static(&self) -> bool {
        !self.static_instances.is_empty()
    }

    /// GPU times of every atlas's one-time `atlas_positions` / `atlas_points` passes.
    pub fn setup_timings(&self) -> impl Iterator<Item = &PassTiming> {
        self.points.iter().flat_map(|p| &p.setup_timings)
    }

    pub fn has_dynamic(&self) -> bool {
        !self.dynamic_instances.is_empty()
    }

    /// Total points splatted per full voxelization (static and dynamic instances; a
    /// sequence counts its first frame, all frames have the same texels).
    pub fn point_count(&self) -> u64 {
        self.static_instances
            .iter()
            .map(|&(p, _, _)| p)
            .chain(self.dynamic_instances.iter().map(|d| d.frames[0].1))
            .map(|p| self.points[p].count)
            .sum()
    }

    /// Point lists built, one per distinct (atlas, sequence frame).
    pub fn point_lists(&self) -> usize {
        self.points.len()
    }

    /// The point lists themselves (their chunks), in build order.
    pub fn lists(&self) -> &[AtlasPoints] {
        &self.points
    }

    /// Takes the dynamic objects' transforms from `scene` (see `VoxelFrame::follow_objects`).
    /// The atlas keeps the texel size of the scale it was built for: a scaled-up object's
    /// points spread apart, so a caller that scales an object makes a new atlas (the viewer
    /// uses the triangle voxelizer).
    pub fn follow_objects(&mut self, scene: &Scene) {
        for d in &mut self.dynamic_instances {
            if let Some(src) = scene.objects.get(d.object_index) {
                d.object.transform = src.transform;
            }
        }
    }

    /// The dynamic objects' model matrices and sequence frames at `t_s`.
    pub fn pose_at(&self, t_s: f32) -> AtlasPose {
        AtlasPose {
            models: self
                .dynamic_instances
                .iter()
                .map(|d| d.object.transform_at(t_s))
                .collect(),
            frames: self
                .dynamic_instances
                .iter()
                .map(|d| d.frame_at(t_s))
                .collect(),
        }
    }

    /// Writes the dynamic objects' pose for frame slot `slot` (after its fence).
    pub fn write_pose(&self, slot: usize, pose: &AtlasPose) {
        for (d, &model) in self.dynamic_instances.iter().zip(&pose.models) {
            d.models.set(slot, model);
        }
        for (d, &f) in self.dynamic_instances.iter().zip(&pose.frames) {
            d.frame.set(slot, f);
        }
    }

    /// The point lists of the static objects, the dynamic ones, or both, with their models
    /// and frames.
    pub fn instances(&self, statics: bool, dynamics: bool) -> Vec<AtlasInstance<'_>> {
        let mut inst = Vec::new();
        if statics {
            inst.extend(self.static_instances.iter().zip(&self.static_coverage).map(
                |(&(p, m, _), c)| AtlasInstance {
                    frames: vec![&self.points[p]],
                    coverage: vec![c.as_ref()],
                    frame: FrameAt::Fixed(0),
                    model: ModelAt::Fixed(m),
                },
            ));
        }
        if dynamics {
            inst.extend(self.dynamic_instances.iter().map(|d| AtlasInstance {
                frames: d.frames.iter().map(|&(_, p)| &self.points[p]).collect(),
                coverage: d.coverage.iter().map(Option::as_ref).collect(),
                frame: FrameAt::PerSlot(d.frame.clone()),
                model: ModelAt::PerSlot(d.models.clone()),
            }));
        }
        inst
    }

    /// Declares `voxelize_atlas` for the static objects, the dynamic ones, or both.
    pub fn add_pass(
        &self,
        g: &mut RenderGraph,
        grid: &VoxelGrid,
        columns: BufferHandle,
        statics: bool,
        dynamics: bool,
        gate: Option<Arc<SlotGate>>,
    ) {
        let inst = self.instances(statics, dynamics);
        add_voxelize_atlas_pass(g, &self.pipelines, grid, columns, &inst, gate);
    }
}

/// Voxelizes the static atlas instances once into a persistent column buffer (resting state
/// `TransferRead`), like [`super::gpu::voxelize_static`] for triangles; returns it with the
/// passes' GPU times.
pub fn voxelize_static_atlas(
    ctx: &Context,
    atlas: &AtlasScene,
    tri_pipes: &super::gpu::VoxelPipelines,
    grid: &VoxelGrid,
    triangles: &super::gpu::TriangleBuffer,
) -> Result<(Buffer, Vec<PassTiming>), GpuVoxelError> {
    let columns = ctx.create_buffer(&BufferDesc {
        name: "voxel static columns".into(),
        size_bytes: super::gpu::column_bytes(grid),
        usage: vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuOnly,
    })?;
    let mut g = RenderGraph::new();
    let h = g.import_buffer(&columns, Access::TransferRead);
    super::gpu::add_voxelize_passes(
        &mut g,
        tri_pipes,
        grid,
        h,
        super::gpu::ColumnBase::Clear,
        &[triangles],
    );
    atlas.add_pass(&mut g, grid, h, true, false, None);
    let timings = run_once(ctx, g)?;
    Ok((columns, timings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_struct_layouts_match_glsl() {
        assert_eq!(std::mem::size_of::<GpuAtlasTriangle>(), 96);
        assert_eq!(std::mem::offset_of!(GpuAtlasTriangle, uv01), 48);
        assert_eq!(std::mem::offset_of!(GpuAtlasTriangle, cell), 80);
        // The push block, against the compute and raster voxelizers' reflected blocks.
        for stages in [
            &["voxelize_atlas.comp"][..],
            &[
                "voxelize_atlas_bits.vert",
                "voxelize_atlas_bits.geom",
                "voxelize_atlas_bits.frag",
            ],
        ] {
            crate::vk::check_push_against(
                stages,
                crate::vk::PushLayout::of::<GpuAtlasVoxelizePush>(),
            )
            .unwrap();
        }
    }

    #[test]
    fn scratch_bands_cover_every_row_once_within_the_chunk() {
        for (w, h, chunk) in [
            (840, 837, 1 << 20),
            (3355, 3355, 1 << 27),
            (7, 5, 16 + 7 * 16),
        ] {
            let bands = scratch_bands(w, h, chunk).expect("a row fits");
            let mut next = 0;
            for &(row0, rows) in &bands {
                assert_eq!(row0, next, "{w}x{h}: bands are contiguous");
                assert!(rows > 0);
                let bytes = SCRATCH_HEADER_BYTES + u64::from(w) * u64::from(rows) * POINT_BYTES;
                assert!(
                    bytes <= chunk,
                    "{w}x{h}: band of {rows} rows is {bytes} bytes"
                );
                next += rows;
            }
            assert_eq!(next, h, "{w}x{h}: every row in a band");
        }
        assert_eq!(scratch_bands(7, 5, 16 + 7 * 16).map(|b| b.len()), Some(5));
        assert_eq!(scratch_bands(840, 837, 1 << 27).map(|b| b.len()), Some(1));
        assert!(
            scratch_bands(8, 5, 16 + 7 * 16).is_none(),
            "a row over the chunk"
        );
        assert!(scratch_bands(8, 5, 8).is_none(), "no room for the header");
    }
}

//! The voxel grid on the GPU: the persistent column image, the triangle voxelizer, and the
//! OR mip chain, all declared as render-graph passes (no pass records a barrier).
//!
//! # Passes (named after their GLSL stems)
//! - `voxel_clear`: zeroes the transient column buffer (or `voxel_copy_static` copies the
//!   once-voxelized static grid into it, so only dynamic objects are voxelized per frame).
//! - `voxelize_triangles`: conservative surface voxelization of world-space triangles by the
//!   exact triangle/box test, bit for bit the CPU reference [`super::voxelize`]. It ORs bits
//!   into a *buffer* with `atomicOr`: storage-image atomics exist only for `R32_UINT`, and a
//!   buffer laid out like the image's tightly packed mip 0 makes the next step one copy.
//! - `voxel_store`: copies the column buffer into mip 0 of the `R32G32B32A32_UINT` image.
//! - `voxel_mip_1` … `voxel_mip_N` (`voxel_mip.comp`): level ℓ = OR of 2×2 texels of ℓ−1,
//!   one dispatch per level, each declared on its own mip subresources.
//!
//! # Image size versus the CPU hierarchy
//! [`BitHierarchy`] sizes level ℓ as `ceil(res / 2^ℓ)`; Vulkan mips are `max(1, size >> ℓ)`
//! (floor), which drops the last odd row or column. The image is therefore allocated at the
//! next power of two per axis ([`image_extent`]) and the grid occupies its top-left
//! `res_x × res_y` corner; the padding stays empty. Then texel `(x, y)` of level ℓ covers the
//! aligned block `[x·2^ℓ, (x+1)·2^ℓ)` exactly as on the CPU, every CPU level is the top-left
//! corner of the GPU level, and both have `mip_count(res_x, res_y)` levels. Traversal code
//! must bound columns by the grid resolution, not the image size. Power-of-two resolutions
//! (the usual choice) waste nothing.
//!
//! [`BitHierarchy`]: super::BitHierarchy

use super::bits::mip_count;
use super::coverage::Coverage;
use super::{VoxelError, VoxelGrid};
use crate::graph::{
    run_once, Access, BufferHandle, GraphError, ImageHandle, OneShotError, RenderGraph, Shader,
    Subresource,
};
use crate::scene::Scene;
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, Image, ImageDesc, MemoryLocation, PassTiming,
    VkError, MAX_FRAMES_IN_FLIGHT,
};
use glam::Vec3;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

pub use crate::scene::{VoxelSettings, Voxelizer};

/// Format of the binary column image: one texel = one column of 128 voxels.
pub const COLUMN_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// Largest workgroup count per dispatch dimension that every Vulkan device supports.
const MAX_GROUPS_X: u32 = 65535;

/// Loop iterations one invocation of the triangle voxelizer may run. Lavapipe (llvmpipe's
/// gallivm) counts the iterations of all loops of a shader invocation together and at 65,535
/// (`LP_MAX_TGSI_LOOP_ITERATIONS`) ends every loop early, without an error: voxels go missing.
/// The margin is for iterations outside the column and depth loops.
const LOOP_BUDGET: u64 = 60_000;

/// Loop iterations per depth step of the triangle voxelizer: the depth loop's own (the
/// overlap test's nine edge-axis tests are written out, not looped).
const ITERATIONS_PER_DEPTH: u64 = 1;

/// How many invocations' worth of loop work the triangle voxelizer needs for a triangle whose
/// world-space bounds are `[lo, hi]` in `grid`: the columns of its voxel bounding box over the
/// columns one invocation can walk within [`LOOP_BUDGET`] at its depth range (the shader's
/// worst case, without the plane bound). A set of triangles is dispatched with
/// `ceil(max loads / group size)` workgroups per triangle (z splits), so no invocation runs
/// past the budget. 0 for triangles outside the grid.
pub fn voxelize_loads(grid: &VoxelGrid, lo: Vec3, hi: Vec3) -> u64 {
    let (a, b) = (grid.world_to_voxel(lo), grid.world_to_voxel(hi));
    let (lo, hi) = (a.min(b), a.max(b));
    let dims_f = grid.extent_voxels().as_vec3();
    // Same bounds as voxelize_core.glsl (NaN compares false there as here).
    if hi.cmplt(Vec3::ZERO).any() || lo.cmpgt(dims_f).any() {
        return 0;
    }
    let first = (lo.ceil() - 1.0).clamp(Vec3::ZERO, dims_f - 1.0).as_uvec3();
    let last = hi.floor().clamp(Vec3::ZERO, dims_f - 1.0).as_uvec3();
    let columns = u64::from(last.x - first.x + 1) * u64::from(last.y - first.y + 1);
    // Per column: its depth steps' iterations plus one of the column loop.
    let per_column = ITERATIONS_PER_DEPTH * u64::from(last.z - first.z + 1) + 1;
    columns.div_ceil((LOOP_BUDGET / per_column).max(1))
}

/// World-space bounds of a triangle.
fn bounds(tri: [Vec3; 3]) -> [Vec3; 2] {
    [
        tri[0].min(tri[1]).min(tri[2]),
        tri[0].max(tri[1]).max(tri[2]),
    ]
}

/// The largest [`voxelize_loads`] of a set of triangle bounds.
fn max_loads(grid: &VoxelGrid, bounds: &[[Vec3; 2]]) -> u64 {
    bounds
        .iter()
        .map(|b| voxelize_loads(grid, b[0], b[1]))
        .max()
        .unwrap_or(0)
}

/// Workgroups per triangle (dispatch z) for a set whose largest load is `loads`.
pub fn voxelize_splits(loads: u64, group_size: u32) -> u32 {
    loads
        .div_ceil(u64::from(group_size.max(1)))
        .clamp(1, u64::from(MAX_GROUPS_X)) as u32
}

/// Errors of the GPU voxel passes.
#[derive(Debug, thiserror::Error)]
pub enum GpuVoxelError {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error(transparent)]
    Voxel(#[from] VoxelError),
    #[error(transparent)]
    Atlas(#[from] super::atlas::AtlasError),
    #[error("a mesh with {mesh_triangles} triangles is too large for the atlas voxelizer (at most {max}); use --voxelizer triangle or split the mesh")]
    TooManyAtlasTriangles { mesh_triangles: usize, max: usize },
    #[error("debug level {level} does not exist: the voxel grid has levels 0..={max}; pass a smaller --debug-level")]
    BadDebugLevel { level: u32, max: u32 },
    #[error(transparent)]
    NoSuchObject(#[from] crate::scene::NoSuchObject),
    #[error("object '{object}' has no atlas: its OBJ-sequence frames differ in topology, so the atlas voxelizer leaves it to the triangle voxelizer; pick another --object")]
    NoAtlas { object: String },
    #[error("one {width}-texel atlas row needs {bytes} bytes of point scratch, above the {max}-byte point-list chunk; use fewer voxels (--voxels) or --voxelizer triangle")]
    AtlasRowTooLarge { width: u32, bytes: u64, max: u64 },
}

impl From<OneShotError> for GpuVoxelError {
    fn from(e: OneShotError) -> Self {
        match e {
            OneShotError::Graph(e) => Self::Graph(e),
            OneShotError::Vk(e) => Self::Vk(e),
        }
    }
}

/// One world-space triangle as the shader reads it (`struct Triangle` in
/// `voxelize_triangles.comp`, std430: three `vec4`); `v[0].w` and `v[1].w` carry its
/// [`Coverage`] (0 and 0: opaque).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTriangle {
    pub v: [[f32; 4]; 3],
}

impl GpuTriangle {
    pub fn new(tri: [Vec3; 3]) -> Self {
        Self {
            v: tri.map(|p| p.extend(0.0).to_array()),
        }
    }

    /// A triangle that sets only the voxels `coverage` keeps.
    pub fn covered(tri: [Vec3; 3], coverage: Coverage) -> Self {
        let mut t = Self::new(tri);
        [t.v[0][3], t.v[1][3]] = coverage.gpu_w();
        t
    }
}

/// Push constants of `voxelize_triangles.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVoxelizePush {
    /// World corner of the grid box (xyz).
    pub grid_min: [f32; 4],
    /// Voxels per meter in the voxel-camera frame, exactly as [`VoxelGrid::world_to_voxel`]
    /// computes it (so the shader repeats its f32 operations).
    pub scale: [f32; 4],
    /// `res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)`.
    pub dims: [u32; 4],
    /// Column-buffer width and height, triangle count, first triangle.
    pub extent: [u32; 4],
}

crate::push_constants!(GpuVoxelizePush {
    grid_min,
    scale,
    dims,
    extent
});

impl GpuVoxelizePush {
    pub fn new(grid: &VoxelGrid, count: u32, first: u32) -> Self {
        let (w, h) = image_extent(grid);
        let ext = grid.extent_voxels();
        Self {
            grid_min: grid.world_min().extend(0.0).to_array(),
            scale: grid.voxels_per_meter().extend(0.0).to_array(),
            dims: [ext.x, ext.y, ext.z, grid.axis().index() as u32],
            extent: [w, h, count, first],
        }
    }
}

/// `(width, height)` of the column image: the next power of two of each grid axis (see the
/// module doc).
pub fn image_extent(grid: &VoxelGrid) -> (u32, u32) {
    (
        grid.res_x().next_power_of_two(),
        grid.res_y().next_power_of_two(),
    )
}

/// The column image of `grid` with its mip hierarchy (also counted by the renderer's memory
/// check before anything is allocated).
pub fn column_image_desc(grid: &VoxelGrid) -> ImageDesc {
    let (w, h) = image_extent(grid);
    let desc = ImageDesc::new_2d("voxel columns", COLUMN_FORMAT, w, h)
        .with_layers(grid.layers())
        .with_mips(mip_count(grid.res_x(), grid.res_y()))
        .with_usage(
            vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST,
        );
    debug_assert_eq!(desc.mip_levels, 1 + w.max(h).trailing_zeros());
    desc
}

/// Bytes of the column buffer (= mip 0 of the image, tightly packed).
pub fn column_bytes(grid: &VoxelGrid) -> u64 {
    let (w, h) = image_extent(grid);
    u64::from(w) * u64::from(h) * u64::from(grid.layers()) * 16
}

/// The pipelines of the voxel passes.
pub struct VoxelPipelines {
    voxelize: ComputePipeline,
    group_size: u32,
    mip: ComputePipeline,
    sampler: crate::vk::Sampler,
}

/// Invocations per triangle of `voxelize_triangles` (see [`VoxelPipelines::with_group_size`]).
///
/// Every group size is exact. Lavapipe ends all loops of an invocation after 65,535
/// iterations of them together, so an invocation that walks a large triangle's box alone (125
/// columns of the bunny box's ceiling at 246 depths each, at 256×255×256 and group size 8)
/// would stop early and lose voxels (10,082 of 333,361 there); large steep triangles reach
/// the same limit at 64. The dispatch splits such triangles over more workgroups
/// ([`voxelize_loads`]).
/// A group of 8 (lavapipe's SIMD width) is faster there; 64 stays the default until the
/// benchmark compares them.
pub const VOXELIZE_GROUP_SIZE: u32 = 64;

impl VoxelPipelines {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        Self::with_group_size(ctx, VOXELIZE_GROUP_SIZE)
    }

    /// Pipelines whose voxelizer shares each triangle's columns among `group_size`
    /// invocations (one workgroup per triangle).
    pub fn with_group_size(ctx: &Context, group_size: u32) -> Result<Self, VkError> {
        let voxelize = ctx.compute_pipeline(
            "voxelize_triangles.comp",
            crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            &crate::spec_constants![local_size_x = group_size.max(1)],
        )?;
        let mip = ctx.compute_pipeline("voxel_mip.comp", None, &[])?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        Ok(Self {
            voxelize,
            group_size: group_size.max(1),
            mip,
            sampler,
        })
    }
}

/// State of the column image between frames: sampled by compute shaders (ray casting).
pub const VOXEL_IMAGE_STATE: Access = Access::Sampled(Shader::Compute);

/// The persistent binary grid image with its full mip chain.
pub struct GpuVoxelGrid {
    pub grid: VoxelGrid,
    pub image: Image,
}

impl GpuVoxelGrid {
    pub fn new(ctx: &Context, grid: &VoxelGrid) -> Result<Self, GpuVoxelError> {
        let desc = column_image_desc(grid);
        let image = ctx.create_image(&desc)?;
        // Imported images must be in their resting state before the first frame.
        ctx.clear_new_image(
            &image,
            vk::ClearColorValue { uint32: [0; 4] },
            VOXEL_IMAGE_STATE.info().layout,
        )?;
        Ok(Self { grid: *grid, image })
    }

    pub fn mip_levels(&self) -> u32 {
        self.image.desc.mip_levels
    }

    /// Imports the image into `g` in its resting state.
    pub fn import(&self, g: &mut RenderGraph) -> ImageHandle {
        g.import_image(&self.image, VOXEL_IMAGE_STATE)
    }
}

/// World-space triangles uploaded once (a device-local storage buffer).
pub struct TriangleBuffer {
    pub buffer: Buffer,
    pub count: u32,
    /// World-space bounds per triangle, to size the dispatch ([`voxelize_loads`]).
    bounds: Vec<[Vec3; 2]>,
}

impl TriangleBuffer {
    /// Validates (finite vertices, like the CPU reference) and uploads `triangles`, opaque.
    pub fn upload(
        ctx: &Context,
        name: &str,
        triangles: &[[Vec3; 3]],
    ) -> Result<Self, GpuVoxelError> {
        Self::upload_covered(ctx, name, triangles, &[])
    }

    /// [`Self::upload`] with each triangle's [`Coverage`] (`coverage[i]` for triangle i; the
    /// triangles past its end are opaque), as [`crate::voxel::coverage::scene_coverage`] gives.
    pub fn upload_covered(
        ctx: &Context,
        name: &str,
        triangles: &[[Vec3; 3]],
        coverage: &[Coverage],
    ) -> Result<Self, GpuVoxelError> {
        check_finite(triangles)?;
        let data: Vec<GpuTriangle> = triangles
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                GpuTriangle::covered(t, coverage.get(i).copied().unwrap_or(Coverage::OPAQUE))
            })
            .collect();
        let buffer = ctx.upload_buffer(
            name,
            bytemuck::cast_slice(&data),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Self {
            buffer,
            count: triangles.len() as u32,
            bounds: triangles.iter().map(|&t| bounds(t)).collect(),
        })
    }
}

pub(super) fn check_finite(triangles: &[[Vec3; 3]]) -> Result<(), VoxelError> {
    for (i, tri) in triangles.iter().enumerate() {
        if let Some(&vertex) = tri.iter().find(|v| !v.is_finite()) {
            return Err(VoxelError::NonFiniteVertex {
                triangle: i,
                vertex,
            });
        }
    }
    Ok(())
}

/// World-space triangles of the scene's objects at time `t_s`; `dynamic` selects the dynamic
/// (moving or animated) objects, or the static ones.
pub fn scene_triangles(scene: &Scene, t_s: f32, dynamic: bool) -> Vec<[Vec3; 3]> {
    let mut out = Vec::new();
    for object in &scene.objects {
        if (object.dynamic || object.is_animated()) != dynamic {
            continue;
        }
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let model = object.transform_at(t_s);
        for tri in mesh.indices.chunks_exact(3) {
            let p = |i: u32| {
                model.transform_point3(mesh.positions.get(i as usize).copied().unwrap_or(Vec3::NAN))
            };
            out.push([p(tri[0]), p(tri[1]), p(tri[2])]);
        }
    }
    out
}

/// How the column buffer starts each time the passes run.
#[derive(Clone, Copy)]
pub enum ColumnBase<'a> {
    /// Empty.
    Clear,
    /// A copy of a persistent column buffer (the static geometry voxelized once), in the
    /// resting state `TransferRead`.
    Copy(&'a Buffer),
}

/// Per frame slot, whether the voxel passes run (the graph skips them where it is closed).
pub use crate::graph::SlotCondition as SlotGate;

/// World-space triangles rewritten by the host per frame slot: one region of `stride` bytes
/// per slot in a host-visible buffer (the frame loop waits on a slot's fence before the host
/// rewrites it), with that slot's triangle count.
pub struct DynamicTriangles {
    pub buffer: Buffer,
    stride: u64,
    capacity: u32,
    counts: Arc<[AtomicU32; MAX_FRAMES_IN_FLIGHT]>,
    /// Per slot, the largest [`voxelize_loads`] of its triangles in `grid`.
    loads: Arc<[AtomicU64; MAX_FRAMES_IN_FLIGHT]>,
    grid: VoxelGrid,
}

impl DynamicTriangles {
    /// Room for `capacity` triangles per slot, voxelized into `grid`.
    pub fn new(
        ctx: &Context,
        name: &str,
        grid: &VoxelGrid,
        capacity: u32,
    ) -> Result<Self, VkError> {
        // Slot offsets must respect minStorageBufferOffsetAlignment (at most 256 bytes).
        let stride = (u64::from(capacity.max(1)) * std::mem::size_of::<GpuTriangle>() as u64)
            .next_multiple_of(256);
        let buffer = ctx.create_buffer(&BufferDesc {
            name: name.into(),
            size_bytes: stride * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        Ok(Self {
            buffer,
            stride,
            capacity,
            counts: Arc::new(std::array::from_fn(|_| AtomicU32::new(0))),
            loads: Arc::new(std::array::from_fn(|_| AtomicU64::new(0))),
            grid: *grid,
        })
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Writes the triangles of frame slot `slot` (call after the slot's fence). Triangles
    /// past the capacity are dropped; returns how many were written.
    pub fn write(&mut self, slot: usize, triangles: &[GpuTriangle]) -> u32 {
        let n = triangles.len().min(self.capacity as usize);
        let offset = (slot as u64 * self.stride) as usize;
        let bytes: &[u8] = bytemuck::cast_slice(&triangles[..n]);
        let Some(m) = self.buffer.mapped_mut() else {
            return 0;
        };
        m[offset..offset + bytes.len()].copy_from_slice(bytes);
        let written: Vec<[Vec3; 2]> = triangles[..n]
            .iter()
            .map(|t| bounds(t.v.map(|p| Vec3::new(p[0], p[1], p[2]))))
            .collect();
        if let Some(l) = self.loads.get(slot) {
            l.store(max_loads(&self.grid, &written), Ordering::Release);
        }
        if let Some(c) = self.counts.get(slot) {
            c.store(n as u32, Ordering::Release);
        }
        n as u32
    }
}

/// A triangle set that the voxelizer reads.
#[derive(Clone, Copy)]
pub enum TriangleSource<'a> {
    /// Uploaded once.
    Fixed(&'a TriangleBuffer),
    /// Rewritten per frame slot.
    PerSlot(&'a DynamicTriangles),
}

/// How a recording closure finds a set's triangles: `(count, loads)` for a slot, `loads`
/// being the set's largest [`voxelize_loads`]. A per-slot set is imported per slot, so its
/// binding is the slot's window.
#[derive(Clone)]
enum SetRange {
    Fixed(u32, u64),
    PerSlot {
        counts: Arc<[AtomicU32; MAX_FRAMES_IN_FLIGHT]>,
        loads: Arc<[AtomicU64; MAX_FRAMES_IN_FLIGHT]>,
    },
}

impl SetRange {
    fn at(&self, slot: usize) -> (u32, u64) {
        match self {
            SetRange::Fixed(n, loads) => (*n, *loads),
            SetRange::PerSlot { counts, loads } => (
                counts.get(slot).map_or(0, |c| c.load(Ordering::Acquire)),
                loads.get(slot).map_or(0, |l| l.load(Ordering::Acquire)),
            ),
        }
    }
}

/// Declares `voxel_clear`/`voxel_copy_static` and `voxelize_triangles` writing a column
/// buffer (`columns`, sized [`column_bytes`]). Each triangle set is one dispatch.
pub fn add_voxelize_passes(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    grid: &VoxelGrid,
    columns: BufferHandle,
    base: ColumnBase<'_>,
    triangles: &[&TriangleBuffer],
) {
    let sources: Vec<_> = triangles
        .iter()
        .map(|&t| TriangleSource::Fixed(t))
        .collect();
    add_voxelize_passes_gated(g, pipelines, grid, columns, base, &sources, None);
}

/// [`add_voxelize_passes`] for fixed and per-slot triangle sets, recording only in slots
/// that `gate` leaves open (every slot when `None`).
pub fn add_voxelize_passes_gated(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    grid: &VoxelGrid,
    columns: BufferHandle,
    base: ColumnBase<'_>,
    triangles: &[TriangleSource<'_>],
    gate: Option<Arc<SlotGate>>,
) {
    match base {
        ColumnBase::Clear => g
            .add_pass("voxel_clear")
            .write(columns, Access::TransferWrite)
            .when(gate.clone())
            .record(move |ctx| ctx.cmd.fill_buffer(ctx.buffer(columns).raw, 0)),
        ColumnBase::Copy(static_columns) => {
            let size = column_bytes(grid);
            let src = g.import_buffer(static_columns, Access::TransferRead);
            g.add_pass("voxel_copy_static")
                .read(src, Access::TransferRead)
                .write(columns, Access::TransferWrite)
                .when(gate.clone())
                .record(move |ctx| {
                    ctx.cmd
                        .copy_buffer(ctx.buffer(src).raw, ctx.buffer(columns).raw, size)
                })
        }
    }
    let read = Access::StorageRead(Shader::Compute);
    let sets: Vec<(BufferHandle, SetRange)> = triangles
        .iter()
        .filter_map(|t| match *t {
            TriangleSource::Fixed(t) if t.count > 0 => Some((
                g.import_buffer(&t.buffer, read),
                SetRange::Fixed(t.count, max_loads(grid, &t.bounds)),
            )),
            TriangleSource::Fixed(_) => None,
            TriangleSource::PerSlot(d) => Some((
                g.import_buffer_per_slot(&d.buffer, d.stride, d.stride, read),
                SetRange::PerSlot {
                    counts: d.counts.clone(),
                    loads: d.loads.clone(),
                },
            )),
        })
        .collect();
    if sets.is_empty() {
        return;
    }
    let pipe = *pipelines.voxelize;
    let group_size = pipelines.group_size;
    let grid = *grid;
    g.add_pass("voxelize_triangles")
        .pipeline(&pipe)
        .bind_one_of(0, sets.iter().map(|s| s.0), read)
        .bind(1, columns, Access::StorageReadWrite(Shader::Compute))
        .when(gate)
        .record(move |ctx| {
            for (h, range) in &sets {
                let (count, loads) = range.at(ctx.slot);
                if count == 0 {
                    continue;
                }
                ctx.bind_with(&pipe, &[(0, *h)]);
                // One workgroup per triangle, rows of MAX_GROUPS_X workgroups past the limit,
                // and z splits so that no invocation outruns lavapipe's loop budget.
                let splits = voxelize_splits(loads, group_size);
                let mut first = 0;
                while first < count {
                    let n = (count - first).min(MAX_GROUPS_X * MAX_GROUPS_X);
                    let push = GpuVoxelizePush::new(&grid, n, first);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    let x = n.min(MAX_GROUPS_X);
                    ctx.cmd.dispatch(x, n.div_ceil(x), splits);
                    first += n;
                }
            }
        });
}

/// Declares `voxel_store` (column buffer → mip 0) and the OR mip chain `voxel_mip_1..`.
pub fn add_store_and_mip_passes(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    voxels: &GpuVoxelGrid,
    columns: BufferHandle,
    image: ImageHandle,
) {
    add_store_and_mip_passes_gated(g, pipelines, voxels, columns, image, None);
}

/// [`add_store_and_mip_passes`] recording only in slots that `gate` leaves open.
pub fn add_store_and_mip_passes_gated(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    voxels: &GpuVoxelGrid,
    columns: BufferHandle,
    image: ImageHandle,
    gate: Option<Arc<SlotGate>>,
) {
    let (w, h) = image_extent(&voxels.grid);
    let layers = voxels.grid.layers();
    g.add_pass("voxel_store")
        .read(columns, Access::TransferRead)
        .write_sub(image, Access::TransferWrite, Subresource::mip(0))
        .when(gate.clone())
        .record(move |ctx| {
            ctx.cmd.copy_buffer_to_image(
                ctx.buffer(columns).raw,
                ctx.image(image).raw,
                vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                },
                0,
                layers,
            )
        });
    mip_passes(
        g,
        pipelines,
        image,
        voxels.mip_levels(),
        (w, h),
        layers,
        gate,
    );
}

/// Declares `voxel_mip_1 .. voxel_mip_{levels-1}`: one dispatch per level, reading level
/// ℓ−1 sampled (`texelFetch`) and writing level ℓ as a storage image.
pub fn add_mip_passes(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    image: ImageHandle,
    levels: u32,
    extent: (u32, u32),
    layers: u32,
) {
    mip_passes(g, pipelines, image, levels, extent, layers, None);
}

fn mip_passes(
    g: &mut RenderGraph,
    pipelines: &VoxelPipelines,
    image: ImageHandle,
    levels: u32,
    extent: (u32, u32),
    layers: u32,
    gate: Option<Arc<SlotGate>>,
) {
    for level in 1..levels {
        let gate = gate.clone();
        let pipe = *pipelines.mip;
        let sampler = pipelines.sampler.raw;
        let (w, h) = ((extent.0 >> level).max(1), (extent.1 >> level).max(1));
        let c = Shader::Compute;
        g.add_pass(&format!("voxel_mip_{level}"))
            .pipeline(&pipe)
            .bind_mip(0, image, level - 1, Access::Sampled(c), Some(sampler))
            .bind_mip(1, image, level, Access::StorageWrite(c), None)
            .when(gate)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(w.div_ceil(8), h.div_ceil(8), layers);
            });
    }
}

/// Voxelizes static geometry once into a persistent column buffer (resting state
/// `TransferRead`), which each frame then copies with [`ColumnBase::Copy`] before inserting
/// the dynamic objects: static geometry is never re-voxelized.
pub fn voxelize_static(
    ctx: &Context,
    pipelines: &VoxelPipelines,
    grid: &VoxelGrid,
    triangles: &TriangleBuffer,
) -> Result<Buffer, GpuVoxelError> {
    voxelize_static_timed(ctx, pipelines, grid, triangles).map(|(b, _)| b)
}

/// [`voxelize_static`], also returning its passes' GPU times.
pub fn voxelize_static_timed(
    ctx: &Context,
    pipelines: &VoxelPipelines,
    grid: &VoxelGrid,
    triangles: &TriangleBuffer,
) -> Result<(Buffer, Vec<PassTiming>), GpuVoxelError> {
    let columns = ctx.create_buffer(&BufferDesc {
        name: "voxel static columns".into(),
        size_bytes: column_bytes(grid),
        usage: vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuOnly,
    })?;
    let mut g = RenderGraph::new();
    let h = g.import_buffer(&columns, Access::TransferRead);
    add_voxelize_passes(&mut g, pipelines, grid, h, ColumnBase::Clear, &[triangles]);
    let timings = run_once(ctx, g)?;
    Ok((columns, timings))
}

impl VoxelSettings {
    /// The grid these settings put around `scene` at `t_s`.
    pub fn grid_for(&self, scene: &Scene, t_s: f32) -> Result<VoxelGrid, VoxelError> {
        let aabb = scene.aabb_at(t_s);
        VoxelGrid::around(
            aabb.min,
            aabb.max,
            &super::GridDesc {
                layers: self.layers,
                max_res_xy: self.max_res_xy,
                ..Default::default()
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_steep_triangles_are_split_within_the_loop_budget() {
        let grid = VoxelGrid::from_box(
            Vec3::ZERO,
            Vec3::ONE,
            Some(super::super::Axis::Z),
            256,
            256,
            2,
        )
        .expect("grid");
        // A voxel-sized triangle: one invocation's worth.
        let h = 0.5 / 256.0;
        assert_eq!(
            voxelize_loads(&grid, Vec3::splat(0.5), Vec3::splat(0.5 + h)),
            1
        );
        assert_eq!(
            voxelize_loads(&grid, Vec3::splat(2.0), Vec3::splat(3.0)),
            0,
            "outside"
        );
        // The whole box: 256 x 256 columns of 256 depths (one iteration each, +1 for the
        // column loop), at most 60,000 / 257 = 233 columns per invocation.
        let loads = voxelize_loads(&grid, Vec3::ZERO, Vec3::ONE);
        assert_eq!(loads, (256u64 * 256).div_ceil(233));
        let splits = voxelize_splits(loads, 64);
        let per_invocation = (256u64 * 256).div_ceil(64 * u64::from(splits));
        assert!(per_invocation * 257 <= LOOP_BUDGET, "{splits} splits");
        assert_eq!(
            voxelize_splits(0, 64),
            1,
            "at least one workgroup per triangle"
        );
        assert_eq!(voxelize_splits(1 << 40, 1), MAX_GROUPS_X);
    }

    #[test]
    fn gpu_struct_layouts_match_glsl() {
        // std430 `struct Triangle { vec4 v[3]; }`.
        assert_eq!(std::mem::size_of::<GpuTriangle>(), 48);
        // The push block, against the shaders' reflected blocks (by name, offset and size).
        for shader in ["voxelize_triangles.comp", "voxelize_attributes.comp"] {
            crate::vk::check_push_against(
                &[shader],
                crate::vk::PushLayout::of::<GpuVoxelizePush>(),
            )
            .unwrap();
        }
    }

    #[test]
    fn shader_degenerate_threshold_is_the_reference_constant() {
        // voxelize_triangles.comp spells DEGENERATE_REL as this bit pattern.
        assert_eq!(
            super::super::voxelize::DEGENERATE_REL.to_bits(),
            0x3089_705f
        );
    }

    #[test]
    fn image_extent_holds_every_cpu_level() {
        for (rx, ry) in [(1, 1), (5, 3), (64, 64), (100, 37), (512, 1)] {
            let grid = VoxelGrid::from_box(
                Vec3::ZERO,
                Vec3::ONE,
                Some(super::super::Axis::Z),
                rx,
                ry,
                1,
            )
            .expect("grid");
            let (w, h) = image_extent(&grid);
            let levels = 1 + w.max(h).trailing_zeros();
            assert_eq!(levels, mip_count(rx, ry));
            for l in 0..levels {
                assert!((w >> l).max(1) >= super::super::bits::mip_extent(rx, l));
                assert!((h >> l).max(1) >= super::super::bits::mip_extent(ry, l));
            }
        }
    }
}

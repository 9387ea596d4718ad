//! Binary voxel grid: placement, CPU reference voxelizer, OR mip hierarchy and ray tests.
//!
//! This module is the CPU twin of the GPU voxel pipeline (Thiedemann 2010,
//! Ch. 4–5). Everything here is plain, safe Rust so tests can hold the GPU against it.
//!
//! # Spaces
//! - **World**: meters.
//! - **Voxel space**: continuous coordinates `[0, res_x) × [0, res_y) × [0, D)`; voxel
//!   `(i, j, k)` is the half-open unit box `[i, i+1) × [j, j+1) × [k, k+1)`. x and y are the
//!   voxel camera's image axes, z is depth. The map from world space is affine
//!   ([`VoxelGrid::world_to_voxel`]), so a ray's parameter `t` is the same in both spaces when
//!   its direction is mapped with [`VoxelGrid::dir_world_to_voxel`].
//! - **Unit cube**: voxel space divided by `(res_x, res_y, D)`; the thesis's
//!   `M = T(½)·S(½)·P·V` (Thiedemann 2010, §5.3.2), directly a texture coordinate.
//!
//! # Bit convention (used by the CPU reference, the LUTs and every shader)
//! The voxel camera is orthographic and looks along the grid box's shortest axis (§4.5).
//! Depth `D = 128 · L`. Depth index `k ∈ [0, D)` counts from the voxel camera's near plane:
//! `layer = k / 128`, `channel = (k mod 128) / 32`, `bit = k mod 32`, least significant bit =
//! nearest. One texel of the `R32G32B32A32_UINT` 2D array image (L layers) holds one column of
//! 128 voxels; R holds the front 32 (thesis §5.3.4: the red channel holds the frontmost voxels).
//!
//! # Hierarchy
//! Mip level ℓ texel = OR of the 2×2 texels of level ℓ−1, all depth bits kept (thesis §5.2,
//! "128 stacked quadtrees"). Level sizes are `ceil(res / 2^ℓ)` down to 1×1; see [`bits`].
//!
//! # Submodules
//! - [`grid`]: grid placement and the world→voxel transforms.
//! - [`bits`]: [`bits::BitGrid`] (CPU copy of the column image) and [`bits::BitHierarchy`].
//! - [`voxelize`]: exact triangle surface voxelizer (Akenine-Möller triangle/box SAT).
//! - [`coverage`]: surfaces of opacity below 1 as stochastic coverage (each touched voxel set
//!   with probability α by a hash of the voxel and the object), shared by every voxelizer.
//! - [`gpu`]: the GPU column image, triangle voxelizer and OR mip chain as render-graph passes.
//! - [`atlas`]: automatic injective per-mesh atlases (packing, coverage rule, density).
//! - [`gpu_atlas`]: the thesis's atlas voxelizer (`atlas_positions`, `atlas_points`,
//!   `voxelize_atlas`), selected by [`gpu::Voxelizer::Atlas`].
//! - [`gpu_atlas_volumes`]: albedo and normal volumes from the same atlas points by layered
//!   rendering (`voxelize_atlas_volumes`, `voxelize_atlas_resolve`), for the GI methods that
//!   read more than occupancy; with emitters or a material volume also the emission and
//!   material volumes (`voxelize_atlas_emission`, `voxelize_atlas_material`).
//! - [`maps`]: the MTL PBR maps (`map_Pr`, `map_Pm`, `map_Ke`) sampled per texel by both
//!   voxelizers' emission and material volumes.
//! - [`gpu_atlas_raster`]: the thesis's raster bit pass (`voxelize_atlas_bits`, logicOp OR),
//!   measured against the compute pass by `voxgi bench voxelize`.
//! - [`ray_mask`]: the 128×128 ray-mask LUT (thesis §5.3.2, Fig. 16) and single-bit LUT (§4.3.1, Fig. 12).
//! - [`traverse`]: hierarchical first hit and visibility (§5.3–§5.3.4), the exact DDA ground
//!   truth, and the 1-bit / 3-bit marching baselines (§6.4.1).

pub mod atlas;
pub mod atlas_view;
pub mod attributes;
pub mod bits;
pub mod coverage;
pub mod debug_view;
pub mod frame;
pub mod gpu;
pub mod gpu_atlas;
pub mod gpu_atlas_raster;
pub mod gpu_atlas_volumes;
pub mod gpu_rays;
pub mod grid;
pub mod maps;
pub mod ray_mask;
pub mod traverse;
pub mod voxelize;

#[cfg(test)]
mod traverse_tests;

pub use bits::{BitGrid, BitHierarchy, Column};
pub use frame::VoxelFrame;
pub use grid::{Axis, GridDesc, VoxelGrid};
pub use traverse::{HitResult, TraversalParams};
pub use voxelize::voxelize_scene;

/// Voxels per column texel (one `R32G32B32A32_UINT` texel = 4 × 32 bits).
pub const COLUMN_BITS: u32 = 128;

/// Errors of the voxel layer. Each message says what was wrong and what to do about it.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VoxelError {
    #[error("voxel grid box has a non-finite corner (min {min:?}, max {max:?}); check the scene bounds or the [voxel] box in the scene file for NaN/Inf")]
    NonFiniteBox { min: glam::Vec3, max: glam::Vec3 },
    #[error("voxel grid box is empty (min {min:?} is above max {max:?} on some axis); swap the corners or give a box that contains the scene")]
    EmptyBox { min: glam::Vec3, max: glam::Vec3 },
    #[error("voxel grid box has zero size on axis {axis} (min {min:?}, max {max:?}); a user box needs a positive extent on every axis")]
    ZeroExtent {
        axis: usize,
        min: glam::Vec3,
        max: glam::Vec3,
    },
    #[error("voxel grid resolution {res_x}×{res_y} with {layers} layer(s) is invalid; each must be between 1 and {max}")]
    BadResolution {
        res_x: u32,
        res_y: u32,
        layers: u32,
        max: u32,
    },
    #[error("voxel grid padding is invalid ({what} = {value}); use a finite value ≥ 0")]
    BadPadding { what: &'static str, value: f32 },
    #[error("GPU read-back has {got} bytes but a {res_x}×{res_y}×{layers} R32G32B32A32_UINT array image needs {expected}; read back all layers of mip 0, tightly packed")]
    ByteSizeMismatch {
        got: usize,
        expected: usize,
        res_x: u32,
        res_y: u32,
        layers: u32,
    },
    #[error("bit grid is {got:?} (res_x, res_y, layers) but the voxel grid needs {expected:?}; create the bit grid with BitGrid::for_grid")]
    GridMismatch {
        got: (u32, u32, u32),
        expected: (u32, u32, u32),
    },
    #[error("triangle {triangle} has a non-finite vertex {vertex:?}; the mesh contains NaN/Inf positions — fix or drop it before voxelizing")]
    NonFiniteVertex { triangle: usize, vertex: glam::Vec3 },
    #[error(
        "triangle {triangle} uses vertex index {index}, but the mesh has only {count} positions"
    )]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        count: usize,
    },
    #[error("index buffer length {len} is not a multiple of 3; triangle lists need three indices per triangle")]
    BadIndexCount { len: usize },
}

//! Benchmarks, measured side by side in one GPU run and printed as ratios (not tests).
//!
//! - [`bench_traverse`] (`voxgi bench traverse`): the thesis's hierarchical ray test against
//!   1-bit marching on the same rays (Thiedemann 2010, §9.3.1).
//! - [`bench_voxelize_sweep`] (`voxgi bench voxelize-sweep`): voxelization time versus
//!   resolution and scene, atlas against triangle voxelizer.
//! - [`bench_voxelize_atlas`] (`voxgi bench voxelize`): the atlas voxelizer's compute and
//!   raster bit passes on one scene.
//! - [`bench_flicker`] (`voxgi bench flicker`): temporal stability of the GI methods along a
//!   moving light's path, against a converged path tracer.
//! - [`bench_soak`] (`voxgi bench soak`): long runs of every method on a moving scene, with
//!   process RSS and the context's GPU memory sampled along the way.
//! - [`reference_cache`]: Mitsuba references made and cached for `voxgi sweep --make-references`.
//! - [`bench_leak`] (`voxgi bench leak`): light leaking through a wall 0.25–4 voxels thick
//!   between two closed rooms, per method (the truth behind the wall is zero).
//! - [`sweep`]: the data of `voxgi sweep` and `voxgi tune` (grid, rows, CSV, Pareto front,
//!   SVG plot, the tuner's choice); [`sweep_traverse`] the rows of its ray-test comparison
//!   (`bench traverse` per scene, radius and test).
//! - [`bench_ssgi`] (`voxgi bench ssgi`): the screen-space GI's scalability table (Oetke
//!   2017 Fig. 4.8): mip filter × GI resolution × samples, per-stage GPU times and errors.
//! - [`bench_dynamic`] (`voxgi bench dynamic`): animated objects voxelized again every frame
//!   over a static scene voxelized once (Thiedemann 2010 §8.2, Figs. 41/42): 0, 3 and 9.
//! - [`bench_scenes`], [`dense_scene`], [`tessellated_cube`]: the generated scenes they run on.

pub mod camera_path;
mod dynamic;
mod flicker;
mod leak;
pub mod plot;
pub mod reference_cache;
mod scenes;
mod soak;
mod ssgi;
pub mod ssgi_limits;
pub mod sweep;
pub mod sweep_traverse;
pub mod temporal;
mod traverse;
mod voxelize;

pub use dynamic::{
    bench_dynamic, dynamic_scene, DynamicBenchDesc, DynamicBenchReport, DynamicBenchRow,
};
pub use flicker::{
    bench_flicker, change_and_flicker, default_methods, FlickerBenchDesc, FlickerReport, FlickerRow,
};
pub use leak::{
    bench_leak, direct_images, leak_methods, leak_row, leak_scene, max_radiance, mean_radiance,
    render_leak_view, LeakBenchDesc, LeakLight, LeakReport, LeakRow, LeakScene,
    DEFAULT_WALLS_VOXELS,
};
pub use scenes::{bench_scenes, dense_scene, tessellated_cube, DENSE_BUNNIES_PER_AXIS};
pub use soak::{
    bench_soak, process_rss_bytes, slope_per_1000, soak_time_s, SoakBenchDesc, SoakReport, SoakRow,
    SoakSample,
};
pub use ssgi::{
    bench_ssgi, load_reference, Span, SsgiBenchDesc, SsgiBenchReport, SsgiBenchRow, StageTime,
};
pub use temporal::scene_at_step;
pub use traverse::{
    bench_radius, bench_traverse, fewest_samples_at_99, gbuffer_points, traverse_rays,
    MethodResult, RadiusResult, TraverseBenchDesc, TraverseBenchReport, TraverseRays,
    DEFAULT_MARCH_STEPS, DEFAULT_RADII_BOX_UNITS,
};
pub use voxelize::{
    bench_voxelize_atlas, bench_voxelize_atlas_chunked, bench_voxelize_sweep, AtlasTimes,
    VoxelizeBenchDesc, VoxelizeBenchReport, VoxelizeSweepDesc, VoxelizeSweepReport,
    VoxelizeSweepRow,
};

use crate::scene::SceneError;
use crate::voxel::atlas::AtlasError;
use crate::voxel::gpu::GpuVoxelError;
use crate::voxel::gpu_rays::RayCastError;
use crate::voxel::VoxelError;

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Voxel(#[from] VoxelError),
    #[error(transparent)]
    Cast(#[from] RayCastError),
    #[error(transparent)]
    Vk(#[from] crate::vk::VkError),
    #[error(transparent)]
    Run(#[from] crate::graph::OneShotError),
    #[error(transparent)]
    GpuVoxel(#[from] GpuVoxelError),
    #[error("the camera sees no geometry: nothing to cast rays from")]
    NoSurface,
    #[error("the traversal benchmark needs at least one hierarchical setting (a start level)")]
    NoHierarchicalParams,
    #[error(
        "traversal benchmark: --radii {radius} is not a ray length; give positive finite \
         lengths in box units (2,4,8 by default)"
    )]
    TraverseRadius { radius: f32 },
    #[error(transparent)]
    Atlas(#[from] AtlasError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    #[error(transparent)]
    Eval(#[from] crate::eval::EvalError),
    #[error(transparent)]
    Settings(#[from] crate::limits::LimitError),
    #[error(
        "the scene has no point or spot light to move: the flicker benchmark moves the first \
         one along a circle; add one to the scene"
    )]
    NoMovableLight,
    #[error("no reference image {}: point --references at the folder that has it, render one with tools/reference (see assets/references/README.md) or choose a scene that has one", path.display())]
    NoReference { path: std::path::PathBuf },
    #[error("--size {size}: the reference {} is {width}x{height}; --size must divide it and the reference must be square (e.g. 32, 64, 128, 256)", path.display())]
    ReferenceSize {
        size: u32,
        width: u32,
        height: u32,
        path: std::path::PathBuf,
    },
    #[error(
        "{bench}: no Mitsuba reference of {scene} at {}; add --make-references to render \
         it with Mitsuba 3 (tools/reference installs it into .venv; seconds to minutes per image)",
        path.display()
    )]
    NoLimitReference {
        bench: &'static str,
        scene: String,
        path: std::path::PathBuf,
    },
    #[error("leak benchmark: a wall of {wall_voxels} voxels cannot be built: {why}")]
    LeakWall { wall_voxels: f32, why: &'static str },
    #[error(
        "leak benchmark, wall of {wall_voxels} voxels: room B's direct light is {max}, not 0 \
         (its shadow maps let light through the wall)"
    )]
    LeakDirect { wall_voxels: f32, max: f32 },
}

//! `voxgi bench voxelize-sweep`: voxelization time versus resolution and scene, atlas against
//! triangle voxelizer ([`bench_voxelize_sweep`]).
//!
//! `voxgi bench voxelize`: the atlas points' binary voxelization both ways, in one run: the
//! renderer's compute pass `voxelize_atlas` (atomicOr into the column buffer) against the
//! thesis's raster pass `voxelize_atlas_bits` (single-bit LUT, logicOp OR; Thiedemann 2010,
//! §4.3.1), with the GPU time of each and whether their bits agree ([`bench_voxelize_atlas`]).

use super::scenes::{bench_scenes, tessellated_cube};
use super::BenchError;
use crate::graph::{readback_buffer, run_once, Access, BufferHandle, RenderGraph};
use crate::scene::Scene;
use crate::stats::median;
use crate::vk::{vk, BufferDesc, Context, ImageDesc, MemoryLocation};
use crate::voxel::atlas::{build_atlas, texel_size_for_voxel, AtlasCache};
use crate::voxel::gpu::{
    add_voxelize_passes, column_bytes, image_extent, scene_triangles, ColumnBase, GpuVoxelError,
    TriangleBuffer, VoxelPipelines, COLUMN_FORMAT, VOXELIZE_GROUP_SIZE,
};
use crate::voxel::gpu_atlas::{
    add_voxelize_atlas_pass, render_atlas_points, AtlasInstance, AtlasPipelines, AtlasScene,
};
use crate::voxel::{GridDesc, VoxelGrid};
use glam::Vec3;
use serde::Serialize;

/// Parameters of `voxgi bench voxelize`.
#[derive(Clone, Debug)]
pub struct VoxelizeBenchDesc {
    /// Voxel grid x/y resolution cap.
    pub resolution: u32,
    /// Depth layers of 128 voxels.
    pub layers: u32,
    /// Runs of each pass; the report gives the median.
    pub repeats: u32,
}

/// The two atlas bit passes on one scene.
#[derive(Clone, Debug, Serialize)]
pub struct VoxelizeBenchReport {
    pub device: String,
    pub grid: [u32; 3],
    /// Atlas points splatted per run.
    pub points: u64,
    pub repeats: u32,
    /// Median GPU ms of `voxelize_atlas` (compute, atomicOr).
    pub compute_ms: f64,
    /// Median GPU ms of `voxelize_atlas_bits` (raster, logicOp OR, clear included).
    pub raster_ms: f64,
    pub raster_over_compute: f64,
    /// Voxels set by the compute pass.
    pub voxels: u64,
    /// 32-bit column words in which the two passes differ (0: the same bits).
    pub differing_words: usize,
}

fn pass_ms(timings: &[crate::vk::PassTiming], name: &str) -> f64 {
    timings
        .iter()
        .filter(|t| t.name == name)
        .map(|t| t.gpu_ms)
        .sum()
}

/// Runs both atlas bit passes `desc.repeats` times on `scene` at time 0 and compares their
/// bits.
pub fn bench_voxelize_atlas(
    ctx: &Context,
    scene: &Scene,
    desc: &VoxelizeBenchDesc,
) -> Result<VoxelizeBenchReport, BenchError> {
    let chunk_bytes = crate::voxel::gpu_atlas::device_chunk_bytes(ctx);
    bench_voxelize_atlas_chunked(ctx, scene, desc, chunk_bytes)
}

/// [`bench_voxelize_atlas`] with point-list chunks of at most `chunk_bytes`
/// ([`crate::voxel::gpu_atlas::render_atlas_points_chunked`]).
pub fn bench_voxelize_atlas_chunked(
    ctx: &Context,
    scene: &Scene,
    desc: &VoxelizeBenchDesc,
    chunk_bytes: u64,
) -> Result<VoxelizeBenchReport, BenchError> {
    let aabb = scene.aabb_at(0.0);
    let grid = VoxelGrid::around(
        aabb.min,
        aabb.max,
        &GridDesc {
            layers: desc.layers,
            max_res_xy: desc.resolution,
            ..Default::default()
        },
    )?;
    let mut cache = AtlasCache::default();
    let atlas = crate::voxel::gpu_atlas::AtlasScene::new_chunked(
        ctx,
        scene,
        0.0,
        &grid,
        &mut cache,
        chunk_bytes,
    )?;
    let raster = crate::voxel::gpu_atlas_raster::AtlasRasterBits::new(ctx)?;
    let size = column_bytes(&grid);
    let (w, h) = image_extent(&grid);
    let layers = grid.layers();
    let buffers = [
        readback_buffer(ctx, "compute bits readback", size)?,
        readback_buffer(ctx, "raster bits readback", size)?,
    ];
    let instances = atlas.instances(true, true);
    let (mut compute_ms, mut raster_ms) = (Vec::new(), Vec::new());
    for _ in 0..desc.repeats.max(1) {
        let mut g = RenderGraph::new();
        let columns = g.create_buffer("voxel column buffer", size);
        g.add_pass("voxel_clear")
            .write(columns, Access::TransferWrite)
            .record(move |ctx| ctx.cmd.fill_buffer(ctx.buffer(columns).raw, 0));
        atlas.add_pass(&mut g, &grid, columns, true, true, None);
        let out = g.import_buffer(&buffers[0], Access::HostRead);
        g.add_pass("bits_readback")
            .read(columns, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd
                    .copy_buffer(ctx.buffer(columns).raw, ctx.buffer(out).raw, size)
            });
        compute_ms.push(pass_ms(&run_once(ctx, g)?, "voxelize_atlas"));

        let mut g = RenderGraph::new();
        let image = g.create_image(
            ImageDesc::new_2d("voxel columns (raster)", COLUMN_FORMAT, w, h).with_layers(layers),
        );
        raster.add_pass(&mut g, &grid, image, &instances);
        let out = g.import_buffer(&buffers[1], Access::HostRead);
        g.add_pass("bits_readback")
            .read(image, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(move |ctx| {
                let extent = vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                };
                let raw = ctx.image(image).raw;
                ctx.cmd
                    .copy_image_to_buffer(raw, extent, 0, layers, ctx.buffer(out).raw)
            });
        raster_ms.push(pass_ms(&run_once(ctx, g)?, "voxelize_atlas_bits"));
    }
    let words = |b: &crate::vk::Buffer| -> Vec<u32> {
        b.mapped()
            .unwrap_or(&[])
            .chunks_exact(4)
            .take(size as usize / 4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let (a, b) = (words(&buffers[0]), words(&buffers[1]));
    let differing_words =
        a.iter().zip(&b).filter(|(x, y)| x != y).count() + a.len().abs_diff(b.len());
    let (compute_ms, raster_ms) = (median(&compute_ms), median(&raster_ms));
    let ext = grid.extent_voxels();
    Ok(VoxelizeBenchReport {
        device: ctx.info.name.clone(),
        grid: [ext.x, ext.y, ext.z],
        points: atlas.point_count(),
        repeats: desc.repeats.max(1),
        compute_ms,
        raster_ms,
        raster_over_compute: raster_ms / compute_ms.max(1e-9),
        voxels: a.iter().map(|w| u64::from(w.count_ones())).sum(),
        differing_words,
    })
}

impl VoxelizeBenchReport {
    pub fn table(&self) -> String {
        format!(
            "atlas voxelization benchmark on {} — grid {}x{}x{}, {} points, median of {} runs\n\
             pass                               GPU ms\n\
             voxelize_atlas (compute, atomicOr) {:>9.3}\n\
             voxelize_atlas_bits (raster, OR)   {:>9.3}\n\
             raster / compute                   {:>9.2}\n\
             voxels set: {}; differing column words: {}\n",
            self.device,
            self.grid[0],
            self.grid[1],
            self.grid[2],
            self.points,
            self.repeats,
            self.compute_ms,
            self.raster_ms,
            self.raster_over_compute,
            self.voxels,
            self.differing_words
        )
    }
}

/// Parameters of `voxgi bench voxelize-sweep`.
#[derive(Clone, Debug)]
pub struct VoxelizeSweepDesc {
    /// Timed runs per measurement (the median is reported).
    pub reps: usize,
    /// x = y resolutions of the scene rows (one depth layer, D = 128).
    pub resolutions: Vec<u32>,
    /// Cube tessellations (quads per face edge) of the same-surface rows, at 128²×128.
    pub tessellations: Vec<u32>,
}

impl Default for VoxelizeSweepDesc {
    fn default() -> Self {
        Self {
            reps: 5,
            resolutions: vec![64, 128, 256, 512],
            tessellations: vec![1, 4],
        }
    }
}

/// One scene at one resolution, both voxelizers.
#[derive(Clone, Debug, Serialize)]
pub struct VoxelizeSweepRow {
    pub scene: String,
    pub resolution: u32,
    pub triangles: usize,
    /// Voxels the triangle voxelizer sets (the exact conservative set).
    pub voxels: u64,
    /// Texels of the scene's distinct atlases.
    pub atlas_texels: u64,
    /// One-time CPU atlas packing.
    pub pack_cpu_ms: f64,
    /// Median GPU ms per voxelization of `voxelize_triangles`.
    pub triangle_ms: f64,
    /// The atlas voxelizer, absent where the device cannot run it (`atlas_error` says why).
    pub atlas: Option<AtlasTimes>,
    pub atlas_error: Option<String>,
}

/// The atlas voxelizer's side of a [`VoxelizeSweepRow`].
#[derive(Clone, Debug, Serialize)]
pub struct AtlasTimes {
    /// Points splatted per voxelization (all instances).
    pub points: u64,
    /// One-time GPU `atlas_positions` + `atlas_points`.
    pub setup_gpu_ms: f64,
    /// Median GPU ms per voxelization of `voxelize_atlas`.
    pub voxelize_ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct VoxelizeSweepReport {
    pub device: String,
    pub reps: usize,
    pub group_size: u32,
    pub rows: Vec<VoxelizeSweepRow>,
}

/// Median GPU ms of the passes named `name` over `reps` one-time runs of what `build`
/// declares.
fn time_pass(
    ctx: &Context,
    reps: usize,
    name: &str,
    build: &dyn Fn(&mut RenderGraph),
) -> Result<f64, BenchError> {
    let mut ms = Vec::new();
    for _ in 0..reps.max(1) {
        let mut g = RenderGraph::new();
        build(&mut g);
        let t = run_once(ctx, g)?;
        ms.push(t.iter().filter(|p| p.name == name).map(|p| p.gpu_ms).sum());
    }
    Ok(median(&ms))
}

/// Voxels the triangle voxelizer sets for `triangles` in `grid` (a read-back popcount).
fn count_voxels(
    ctx: &Context,
    pipes: &VoxelPipelines,
    grid: &VoxelGrid,
    triangles: &TriangleBuffer,
) -> Result<u64, BenchError> {
    let columns = ctx.create_buffer(&BufferDesc {
        name: "bench columns (read back)".into(),
        size_bytes: column_bytes(grid),
        usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    })?;
    let mut g = RenderGraph::new();
    let h = g.import_buffer(&columns, Access::HostRead);
    add_voxelize_passes(&mut g, pipes, grid, h, ColumnBase::Clear, &[triangles]);
    g.mark_output(h);
    run_once(ctx, g)?;
    let count = columns.mapped().map_or(0, |m| {
        m.chunks_exact(4)
            .map(|w| u64::from(u32::from_ne_bytes([w[0], w[1], w[2], w[3]]).count_ones()))
            .sum()
    });
    Ok(count)
}

/// Median GPU ms per voxelization of `triangles` into `grid` by the triangle voxelizer.
fn time_triangles(
    ctx: &Context,
    reps: usize,
    pipes: &VoxelPipelines,
    grid: &VoxelGrid,
    triangles: &TriangleBuffer,
) -> Result<f64, BenchError> {
    let size = column_bytes(grid);
    time_pass(ctx, reps, "voxelize_triangles", &|g| {
        let c = g.create_buffer("columns", size);
        add_voxelize_passes(g, pipes, grid, c, ColumnBase::Clear, &[triangles]);
        g.mark_output(c);
    })
}

/// Median GPU ms per voxelization by the atlas voxelizer of what `splat` declares into the
/// column buffer.
fn time_atlas(
    ctx: &Context,
    reps: usize,
    pipes: &VoxelPipelines,
    grid: &VoxelGrid,
    splat: &dyn Fn(&mut RenderGraph, BufferHandle),
) -> Result<f64, BenchError> {
    let size = column_bytes(grid);
    time_pass(ctx, reps, "voxelize_atlas", &|g| {
        let c = g.create_buffer("columns", size);
        add_voxelize_passes(g, pipes, grid, c, ColumnBase::Clear, &[]);
        splat(g, c);
        g.mark_output(c);
    })
}

/// Voxelization time versus x,y resolution and scene ([`bench_scenes`]), atlas and triangle
/// voxelizer side by side in one run, and the atlas cost on the same surface (a cube)
/// tessellated 1× and 16× (`desc.tessellations`). Atlas times are the per-voxelization
/// `voxelize_atlas` splat of rigid objects; the one-time atlas work is listed apart.
pub fn bench_voxelize_sweep(
    ctx: &Context,
    desc: &VoxelizeSweepDesc,
) -> Result<VoxelizeSweepReport, BenchError> {
    let pipes = VoxelPipelines::new(ctx)?;
    let atlas_pipes = AtlasPipelines::new(ctx)?;
    let mut rows = Vec::new();
    for (name, scene) in bench_scenes()? {
        let mut tris = scene_triangles(&scene, 0.0, false);
        tris.extend(scene_triangles(&scene, 0.0, true));
        let buf = TriangleBuffer::upload(ctx, "bench triangles", &tris)?;
        let aabb = scene.aabb_at(0.0);
        let pad = Vec3::splat(0.01 * aabb.extent().max_element());
        for &res in &desc.resolutions {
            let grid = VoxelGrid::from_box(aabb.min - pad, aabb.max + pad, None, res, res, 1)?;
            let t0 = std::time::Instant::now();
            let mut cache = AtlasCache::default();
            let texel_m = texel_size_for_voxel(grid.voxel_size_m().min_element());
            let mut texels = 0u64;
            let mut seen = Vec::new();
            for o in &scene.objects {
                let Some(m) = scene.meshes.get(o.mesh) else {
                    continue;
                };
                let scale = o.transform_components_at(0.0).scale;
                let a = cache.get(&m.name, &m.positions, &m.indices, scale, texel_m)?;
                if !seen.iter().any(|s| std::sync::Arc::ptr_eq(s, &a)) {
                    texels += u64::from(a.width) * u64::from(a.height);
                    seen.push(a);
                }
            }
            let pack_cpu_ms = t0.elapsed().as_secs_f64() * 1e3;
            let voxels = count_voxels(ctx, &pipes, &grid, &buf)?;
            let triangle_ms = time_triangles(ctx, desc.reps, &pipes, &grid, &buf)?;
            let (atlas, atlas_error) = match AtlasScene::new(ctx, &scene, 0.0, &grid, &mut cache) {
                Ok(a) => {
                    let t = AtlasTimes {
                        points: a.point_count(),
                        setup_gpu_ms: a.setup_timings().map(|t| t.gpu_ms).sum(),
                        voxelize_ms: time_atlas(ctx, desc.reps, &pipes, &grid, &|g, c| {
                            a.add_pass(g, &grid, c, true, true, None)
                        })?,
                    };
                    (Some(t), None)
                }
                Err(e @ GpuVoxelError::AtlasRowTooLarge { .. }) => (None, Some(e.to_string())),
                Err(e) => return Err(e.into()),
            };
            rows.push(VoxelizeSweepRow {
                scene: name.clone(),
                resolution: res,
                triangles: tris.len(),
                voxels,
                atlas_texels: texels,
                pack_cpu_ms,
                triangle_ms,
                atlas,
                atlas_error,
            });
        }
    }
    // Same surface, more triangles, at 128²×128.
    let grid = VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, None, 128, 128, 1)?;
    let texel_m = texel_size_for_voxel(grid.voxel_size_m().min_element());
    for &n in &desc.tessellations {
        let (pos, idx) = tessellated_cube(n);
        let tris: Vec<[Vec3; 3]> = idx
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| pos[t[k] as usize]))
            .collect();
        let t0 = std::time::Instant::now();
        let atlas = build_atlas("cube", &pos, &idx, Vec3::ONE, texel_m)?;
        let pack_cpu_ms = t0.elapsed().as_secs_f64() * 1e3;
        let buf = TriangleBuffer::upload(ctx, "bench triangles", &tris)?;
        let points = render_atlas_points(ctx, &atlas_pipes, &atlas, &pos, &idx)?;
        let voxels = count_voxels(ctx, &pipes, &grid, &buf)?;
        let instances = [AtlasInstance::rigid(&points, glam::Mat4::IDENTITY)];
        let triangle_ms = time_triangles(ctx, desc.reps, &pipes, &grid, &buf)?;
        let voxelize_ms = time_atlas(ctx, desc.reps, &pipes, &grid, &|g, c| {
            add_voxelize_atlas_pass(g, &atlas_pipes, &grid, c, &instances, None)
        })?;
        rows.push(VoxelizeSweepRow {
            scene: format!("cube {}x", n * n),
            resolution: 128,
            triangles: tris.len(),
            voxels,
            atlas_texels: u64::from(atlas.width) * u64::from(atlas.height),
            pack_cpu_ms,
            triangle_ms,
            atlas: Some(AtlasTimes {
                points: points.count,
                setup_gpu_ms: points.setup_timings.iter().map(|t| t.gpu_ms).sum(),
                voxelize_ms,
            }),
            atlas_error: None,
        });
    }
    Ok(VoxelizeSweepReport {
        device: ctx.info.name.clone(),
        reps: desc.reps,
        group_size: VOXELIZE_GROUP_SIZE,
        rows,
    })
}

impl VoxelizeSweepReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "voxelization sweep on {} (D = 128, median of {} runs, triangle voxelizer \
             group size {})\n\
             GPU ms per voxelization: tri = voxelize_triangles, atlas = voxelize_atlas (rigid \
             objects' points splatted);\n\
             one-time atlas work apart: pack = CPU packing, setup = GPU atlas_positions + \
             atlas_points\n\n",
            self.device, self.reps, self.group_size
        );
        s += &format!(
            "{:<14} {:>5} {:>9} {:>9} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>11}\n",
            "scene",
            "res",
            "triangles",
            "voxels",
            "points",
            "texels",
            "pack ms",
            "setup ms",
            "tri ms",
            "atlas ms",
            "atlas/tri"
        );
        let mut notes = Vec::new();
        for r in &self.rows {
            let na = || format!("{:>9}", "-");
            let (points, setup, atlas, ratio) = match &r.atlas {
                Some(a) => (
                    format!("{:>10}", a.points),
                    format!("{:>9.2}", a.setup_gpu_ms),
                    format!("{:>9.3}", a.voxelize_ms),
                    format!("{:>11.3}", a.voxelize_ms / r.triangle_ms.max(1e-9)),
                ),
                None => (format!("{:>10}", "-"), na(), na(), format!("{:>11}", "-")),
            };
            if let Some(e) = &r.atlas_error {
                notes.push(format!("{} {}²: no atlas row: {e}", r.scene, r.resolution));
            }
            s += &format!(
                "{:<14} {:>5} {:>9} {:>9} {points} {:>10} {:>9.1} {setup} {:>9.3} {atlas} {ratio}\n",
                r.scene,
                format!("{}²", r.resolution),
                r.triangles,
                r.voxels,
                r.atlas_texels,
                r.pack_cpu_ms,
                r.triangle_ms,
            );
        }
        for n in notes {
            s += &format!("{n}\n");
        }
        s
    }
}

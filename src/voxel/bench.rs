//! `voxgi bench voxelize-sweep`: voxelization time versus resolution and scene, atlas against
//! triangle voxelizer ([`bench_voxelize_sweep`]); `voxgi bench voxelize`: the atlas voxelizer's
//! compute and raster bit passes on one scene ([`bench_voxelize_atlas`]).
//!
//! `voxgi bench traverse`: the thesis's speed comparison (§9.3.1, Fig. 44/45) measured side by
//! side in one GPU run. Rays start at the camera-visible surface points of a scene (a G-buffer
//! traced on the CPU), offset along the normal (§4.4), cosine-distributed around it, with a
//! length limited by a radius. The hierarchical test and 1-bit marching cast the same rays.
//!
//! `voxgi bench voxelize`: the atlas points' binary voxelization both ways, in one run: the
//! renderer's compute pass `voxelize_atlas` (atomicOr into the column buffer) against the
//! thesis's raster pass `voxelize_atlas_bits` (single-bit LUT, logicOp OR; digest §3.3),
//! with the GPU time of each and whether their bits agree.

use super::atlas::{build_atlas, texel_size_for_voxel, AtlasCache, AtlasError};
use super::gpu::{
    add_voxelize_passes, column_bytes, run_once, scene_triangles, ColumnBase, GpuVoxelError,
    TriangleBuffer, VoxelPipelines, VOXELIZE_GROUP_SIZE,
};
use super::gpu_atlas::{
    add_voxelize_atlas_pass, render_atlas_points, AtlasInstance, AtlasPipelines, AtlasScene,
};
use super::gpu_rays::{GpuRay, RayCastError, RayMethod, VoxelRayCaster};
use super::{
    voxelize_scene, BitGrid, BitHierarchy, GridDesc, TraversalParams, VoxelError, VoxelGrid,
};
use crate::graph::{Access, BufferHandle, RenderGraph};
use crate::scene::{Scene, SceneError};
use crate::vk::{vk, BufferDesc, Context, MemoryLocation};
use glam::Vec3;
use serde::Serialize;

/// Parameters of the benchmark.
#[derive(Clone, Debug)]
pub struct TraverseBenchDesc {
    /// Voxel grid x/y resolution cap (depth 128).
    pub resolution: u32,
    /// G-buffer size (points = width × height, background excluded).
    pub gbuffer_size: u32,
    /// Rays per G-buffer point.
    pub rays_per_point: u32,
    /// Radii in units of the thesis's test box (≈ 6 units wide), scaled to the scene:
    /// radius_m = r / 6 × the scene's largest extent.
    pub radii_box_units: Vec<f32>,
    /// Marching sample counts to try.
    pub march_steps: Vec<u32>,
    /// Normal offset, in voxel diagonals (thesis §4.4, k₁).
    pub normal_offset_voxels: f32,
    pub params: TraversalParams,
}

impl Default for TraverseBenchDesc {
    fn default() -> Self {
        Self {
            resolution: 128,
            gbuffer_size: 128,
            rays_per_point: 16,
            radii_box_units: vec![2.0, 4.0, 8.0],
            march_steps: vec![8, 16, 32, 64, 128, 256, 512],
            normal_offset_voxels: 1.0,
            params: TraversalParams {
                start_level: 1,
                max_iterations: 1024,
            },
        }
    }
}

/// One method at one radius.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    pub method: String,
    pub gpu_ms: f64,
    pub rays_per_s: f64,
    pub mean_steps: f64,
    /// Share of rays whose hit/miss agrees with the hierarchical test.
    pub agreement: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct RadiusResult {
    pub radius_box_units: f32,
    pub radius_m: f32,
    pub rays: usize,
    pub hit_fraction: f64,
    pub methods: Vec<MethodResult>,
    /// Fewest marching samples whose results agree with the hierarchical test on ≥ 99% of
    /// rays, if any tried count does.
    pub march_steps_for_99: Option<u32>,
    /// GPU time of that marching run divided by the hierarchical test's.
    pub speedup_at_99: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct TraverseBenchReport {
    pub device: String,
    pub grid: [u32; 3],
    pub points: usize,
    pub radii: Vec<RadiusResult>,
}

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Voxel(#[from] VoxelError),
    #[error(transparent)]
    Cast(#[from] RayCastError),
    #[error(transparent)]
    Vk(#[from] crate::vk::VkError),
    #[error(transparent)]
    GpuVoxel(#[from] super::gpu::GpuVoxelError),
    #[error("the camera sees no geometry: nothing to cast rays from")]
    NoSurface,
    #[error(transparent)]
    Atlas(#[from] AtlasError),
    #[error(transparent)]
    Scene(#[from] SceneError),
}

/// World-space triangles of the scene at time 0.
fn triangles(scene: &Scene) -> Vec<[Vec3; 3]> {
    let mut out = Vec::new();
    for o in &scene.objects {
        let Some(mesh) = scene.meshes.get(o.mesh_at(0.0)) else {
            continue;
        };
        let m = o.transform_at(0.0);
        for t in mesh.indices.chunks_exact(3) {
            let p = |i: u32| m.transform_point3(mesh.positions[i as usize]);
            out.push([p(t[0]), p(t[1]), p(t[2])]);
        }
    }
    out
}

/// Möller–Trumbore: distance along a unit ray to the triangle, if hit in front.
fn intersect(o: Vec3, d: Vec3, t: &[Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let dist = e2.dot(q) * inv;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 1e-6).then_some(dist)
}

/// Camera-visible surface points and normals (facing the camera): a CPU-traced G-buffer.
pub fn gbuffer_points(scene: &Scene, size: u32) -> Vec<(Vec3, Vec3)> {
    let tris = triangles(scene);
    let inv = scene.camera.view_proj(1.0).inverse();
    let mut out = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let ndc = |z: f32| {
                let p = inv
                    * glam::Vec4::new(
                        (x as f32 + 0.5) / size as f32 * 2.0 - 1.0,
                        (y as f32 + 0.5) / size as f32 * 2.0 - 1.0,
                        z,
                        1.0,
                    );
                p.truncate() / p.w
            };
            let o = scene.camera.position;
            let d = (ndc(1.0) - ndc(0.0)).normalize();
            let mut best: Option<(f32, usize)> = None;
            for (i, t) in tris.iter().enumerate() {
                if let Some(dist) = intersect(o, d, t) {
                    if best.map_or(true, |(b, _)| dist < b) {
                        best = Some((dist, i));
                    }
                }
            }
            if let Some((dist, i)) = best {
                let t = &tris[i];
                let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
                if n.dot(d) > 0.0 {
                    n = -n;
                }
                out.push((o + d * dist, n));
            }
        }
    }
    out
}

/// Cosine-distributed direction around `n` from two uniform numbers (Malley's method).
fn cosine_dir(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
    let t = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let b1 = n.cross(t).normalize();
    let b2 = n.cross(b1);
    (b1 * local.x + b2 * local.y + n * local.z).normalize()
}

/// Radical inverse in base 2 (Hammersley's second coordinate).
fn radical_inverse(mut i: u32) -> f32 {
    i = i.reverse_bits();
    i as f32 * (1.0 / 4_294_967_296.0)
}

/// Runs the benchmark on `scene`.
pub fn bench_traverse(
    ctx: &Context,
    scene: &Scene,
    desc: &TraverseBenchDesc,
) -> Result<TraverseBenchReport, BenchError> {
    let aabb = scene.aabb_at(0.0);
    let grid = VoxelGrid::around(
        aabb.min,
        aabb.max,
        &GridDesc {
            max_res_xy: desc.resolution,
            ..Default::default()
        },
    )?;
    let mut bits = BitGrid::for_grid(&grid);
    voxelize_scene(&grid, &mut bits, scene, 0.0)?;
    let h = BitHierarchy::build(bits);
    let points = gbuffer_points(scene, desc.gbuffer_size);
    if points.is_empty() {
        return Err(BenchError::NoSurface);
    }
    let offset = desc.normal_offset_voxels * grid.voxel_diagonal_m();
    let scene_size = aabb.extent().max_element();
    let caster = VoxelRayCaster::new(ctx, &h)?;
    let mut radii = Vec::new();
    let result = (|| -> Result<(), BenchError> {
        for &r in &desc.radii_box_units {
            let radius_m = r / 6.0 * scene_size;
            let mut rays = Vec::with_capacity(points.len() * desc.rays_per_point as usize);
            for (pi, &(p, n)) in points.iter().enumerate() {
                // Per-point Cranley–Patterson rotation of a Hammersley set.
                let rot = (
                    radical_inverse(pi as u32 * 7 + 1),
                    radical_inverse(pi as u32 * 13 + 3),
                );
                for j in 0..desc.rays_per_point {
                    let u1 = ((j as f32 + 0.5) / desc.rays_per_point as f32 + rot.0).fract();
                    let u2 = (radical_inverse(j) + rot.1).fract();
                    let d = cosine_dir(n, u1, u2);
                    let o = grid.world_to_voxel(p + n * offset);
                    rays.push(GpuRay::new(o, grid.dir_world_to_voxel(d), radius_m));
                }
            }
            let mut methods = vec![RayMethod::Hierarchical(desc.params)];
            methods.extend(desc.march_steps.iter().map(|&s| RayMethod::March1(s)));
            let batches = caster.cast(ctx, &rays, &methods)?;
            let reference = &batches[0];
            let hits = reference.hits.iter().filter(|h| h.hit).count();
            let mut results = Vec::new();
            let mut steps_99 = None;
            let mut speedup = None;
            for b in &batches {
                let agree = b
                    .hits
                    .iter()
                    .zip(&reference.hits)
                    .filter(|(a, r)| a.hit == r.hit)
                    .count();
                let agreement = agree as f64 / rays.len() as f64;
                let mean_steps =
                    b.hits.iter().map(|h| f64::from(h.steps)).sum::<f64>() / rays.len() as f64;
                if let RayMethod::March1(s) = b.method {
                    if agreement >= 0.99 && steps_99.is_none() {
                        steps_99 = Some(s);
                        speedup = Some(b.gpu_ms / reference.gpu_ms.max(1e-9));
                    }
                }
                results.push(MethodResult {
                    method: b.method.name(),
                    gpu_ms: b.gpu_ms,
                    rays_per_s: rays.len() as f64 / (b.gpu_ms.max(1e-9) * 1e-3),
                    mean_steps,
                    agreement,
                });
            }
            radii.push(RadiusResult {
                radius_box_units: r,
                radius_m,
                rays: rays.len(),
                hit_fraction: hits as f64 / rays.len() as f64,
                methods: results,
                march_steps_for_99: steps_99,
                speedup_at_99: speedup,
            });
        }
        Ok(())
    })();
    caster.destroy(ctx);
    result?;
    let b = h.base();
    Ok(TraverseBenchReport {
        device: ctx.info.name.clone(),
        grid: [b.res_x(), b.res_y(), b.depth()],
        points: points.len(),
        radii,
    })
}

impl TraverseBenchReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "traversal benchmark on {} — grid {}x{}x{}, {} surface points\n",
            self.device, self.grid[0], self.grid[1], self.grid[2], self.points
        );
        for r in &self.radii {
            s += &format!(
                "\nradius {} box units ({:.3} m): {} rays, {:.1}% hit\n",
                r.radius_box_units,
                r.radius_m,
                r.rays,
                100.0 * r.hit_fraction
            );
            s += &format!(
                "  {:<14} {:>10} {:>12} {:>10} {:>10}\n",
                "method", "GPU ms", "Mrays/s", "steps/ray", "agree %"
            );
            for m in &r.methods {
                s += &format!(
                    "  {:<14} {:>10.3} {:>12.2} {:>10.2} {:>10.2}\n",
                    m.method,
                    m.gpu_ms,
                    m.rays_per_s * 1e-6,
                    m.mean_steps,
                    100.0 * m.agreement
                );
            }
            match (r.march_steps_for_99, r.speedup_at_99) {
                (Some(n), Some(x)) => {
                    s += &format!("  1-bit marching needs {n} samples to agree on >= 99% of rays; hierarchical is {x:.2}x faster than that\n")
                }
                _ => s += "  no tried marching sample count agrees on >= 99% of rays\n",
            }
        }
        s
    }
}

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

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied().unwrap_or(0.0)
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
    let chunk_bytes = super::gpu_atlas::device_chunk_bytes(ctx);
    bench_voxelize_atlas_chunked(ctx, scene, desc, chunk_bytes)
}

/// [`bench_voxelize_atlas`] with point-list chunks of at most `chunk_bytes`
/// ([`super::gpu_atlas::render_atlas_points_chunked`]).
pub fn bench_voxelize_atlas_chunked(
    ctx: &Context,
    scene: &Scene,
    desc: &VoxelizeBenchDesc,
    chunk_bytes: u64,
) -> Result<VoxelizeBenchReport, BenchError> {
    use super::gpu::{column_bytes, image_extent, readback_buffer, run_once, COLUMN_FORMAT};
    use crate::graph::{Access, RenderGraph};
    use crate::vk::{vk, ImageDesc};
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
    let mut cache = super::atlas::AtlasCache::default();
    let atlas =
        super::gpu_atlas::AtlasScene::new_chunked(ctx, scene, 0.0, &grid, &mut cache, chunk_bytes)?;
    let raster = match super::gpu_atlas_raster::AtlasRasterBits::new(ctx) {
        Ok(r) => r,
        Err(e) => {
            atlas.destroy(ctx);
            return Err(e.into());
        }
    };
    let size = column_bytes(&grid);
    let (w, h) = image_extent(&grid);
    let layers = grid.layers();
    let mut buffers = Vec::new();
    let result = (|| -> Result<VoxelizeBenchReport, BenchError> {
        buffers.push(readback_buffer(ctx, "compute bits readback", size)?);
        buffers.push(readback_buffer(ctx, "raster bits readback", size)?);
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
                ImageDesc::new_2d("voxel columns (raster)", COLUMN_FORMAT, w, h)
                    .with_layers(layers),
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
        let (compute_ms, raster_ms) = (median(compute_ms), median(raster_ms));
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
    })();
    for b in buffers {
        ctx.destroy_buffer(b);
    }
    raster.destroy(ctx);
    atlas.destroy(ctx);
    result
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

/// The scene rows' scenes: Cornell, bunny-in-box and [`dense_scene`].
pub fn bench_scenes() -> Result<Vec<(String, Scene)>, BenchError> {
    let scenes_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    Ok(vec![
        ("cornell".into(), crate::scene::load_scene_arg(None)?),
        (
            "bunny-in-box".into(),
            Scene::load(scenes_dir.join("cornell_bunny.toml"))?,
        ),
        ("dense-bunnies".into(), dense_scene(&scenes_dir)?),
    ])
}

/// Bunnies per axis of [`dense_scene`].
pub const DENSE_BUNNIES_PER_AXIS: u32 = 4;

/// The dense generated scene: the Cornell walls around a 4×4×4 grid of Stanford bunnies
/// (64 instances of `assets/meshes/bunny.obj`, 3,674 triangles each, 0.1 m tall; 235,146
/// triangles with the walls), one per cell of the box's interior, each turned a further 30°
/// about y than the previous so that neighbours differ. Deterministic; `scenes_dir` resolves
/// the mesh path. The instances share one atlas, so the atlas voxelizer packs it once and
/// splats its points 64 times.
pub fn dense_scene(scenes_dir: &std::path::Path) -> Result<Scene, BenchError> {
    let n = DENSE_BUNNIES_PER_AXIS;
    // bunny.obj spans x [-4.96, 4.95], y [0, 9.65], z [-3.73, 3.81] (cornell_bunny.toml):
    // within 6.26 of its vertical axis, so at any turn it stays inside its cell.
    let cell_m = 0.54 / n as f32;
    let scale = 0.95 * 0.5 * cell_m / 6.26;
    let mut toml = String::from(
        "[camera]\nposition = [0.278, 0.273, -0.800]\ntarget = [0.278, 0.273, 0.0]\n\
         fov_y_deg = 39.3\nnear = 0.01\nfar = 10.0\n\n\
         [[lights]]\nkind = \"spot\"\nposition = [0.278, 0.540, 0.2796]\n\
         direction = [0.0, -1.0, 0.0]\nintensity_w_sr = [1.0, 1.0, 1.0]\n\
         cutoff_deg = 50.0\nbeam_deg = 40.0\n\n\
         [[objects]]\nname = \"walls\"\nbuiltin = \"cornell_walls\"\n",
    );
    let mut k = 0;
    for j in 0..n {
        for i in 0..n {
            for l in 0..n {
                let x = 0.005 + (i as f32 + 0.5) * cell_m;
                // A millimetre up: the mesh's base dips just below y = 0.
                let y = 0.001 + j as f32 * cell_m;
                let z = 0.01 + (l as f32 + 0.5) * cell_m;
                toml += &format!(
                    "\n[[objects]]\nname = \"bunny_{k}\"\nmesh = \"../meshes/bunny.obj\"\n\
                     translate = [{x}, {y}, {z}]\nrotate_deg = [0.0, {}, 0.0]\n\
                     scale = {scale}\nmaterial = {{ albedo = [0.73, 0.73, 0.73] }}\n",
                    (30 * k) % 360
                );
                k += 1;
            }
        }
    }
    Ok(Scene::from_toml_str(
        &toml,
        std::path::Path::new("<dense generated scene>"),
        scenes_dir,
    )?)
}

/// Median of the finite values; 0 when none.
fn median_ms(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
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
    Ok(median_ms(ms))
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
    let run = run_once(ctx, g);
    let count = columns.mapped().map_or(0, |m| {
        m.chunks_exact(4)
            .map(|w| u64::from(u32::from_ne_bytes([w[0], w[1], w[2], w[3]]).count_ones()))
            .sum()
    });
    ctx.destroy_buffer(columns);
    run?;
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
    let atlas_pipes = match AtlasPipelines::new(ctx) {
        Ok(p) => p,
        Err(e) => {
            pipes.destroy(ctx);
            return Err(e.into());
        }
    };
    let rows = (|| -> Result<Vec<VoxelizeSweepRow>, BenchError> {
        let mut rows = Vec::new();
        for (name, scene) in bench_scenes()? {
            let mut tris = scene_triangles(&scene, 0.0, false);
            tris.extend(scene_triangles(&scene, 0.0, true));
            let buf = TriangleBuffer::upload(ctx, "bench triangles", &tris)?;
            let aabb = scene.aabb_at(0.0);
            let pad = Vec3::splat(0.01 * aabb.extent().max_element());
            let r = (|| -> Result<(), BenchError> {
                for &res in &desc.resolutions {
                    let grid =
                        VoxelGrid::from_box(aabb.min - pad, aabb.max + pad, None, res, res, 1)?;
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
                    let (atlas, atlas_error) =
                        match AtlasScene::new(ctx, &scene, 0.0, &grid, &mut cache) {
                            Ok(a) => {
                                let t = (|| {
                                    Ok::<_, BenchError>(AtlasTimes {
                                        points: a.point_count(),
                                        setup_gpu_ms: a.setup_timings().map(|t| t.gpu_ms).sum(),
                                        voxelize_ms: time_atlas(
                                            ctx,
                                            desc.reps,
                                            &pipes,
                                            &grid,
                                            &|g, c| a.add_pass(g, &grid, c, true, true, None),
                                        )?,
                                    })
                                })();
                                a.destroy(ctx);
                                (Some(t?), None)
                            }
                            Err(e @ GpuVoxelError::AtlasRowTooLarge { .. }) => {
                                (None, Some(e.to_string()))
                            }
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
                Ok(())
            })();
            buf.destroy(ctx);
            r?;
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
            let row = (|| {
                let points = render_atlas_points(ctx, &atlas_pipes, &atlas, &pos, &idx)?;
                let r = (|| {
                    let voxels = count_voxels(ctx, &pipes, &grid, &buf)?;
                    let instances = [AtlasInstance::rigid(&points, glam::Mat4::IDENTITY)];
                    let triangle_ms = time_triangles(ctx, desc.reps, &pipes, &grid, &buf)?;
                    let voxelize_ms = time_atlas(ctx, desc.reps, &pipes, &grid, &|g, c| {
                        add_voxelize_atlas_pass(g, &atlas_pipes, &grid, c, &instances, None)
                    })?;
                    Ok::<_, BenchError>(VoxelizeSweepRow {
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
                    })
                })();
                points.destroy(ctx);
                r
            })();
            buf.destroy(ctx);
            rows.push(row?);
        }
        Ok(rows)
    })();
    atlas_pipes.destroy(ctx);
    pipes.destroy(ctx);
    Ok(VoxelizeSweepReport {
        device: ctx.info.name.clone(),
        reps: desc.reps,
        group_size: VOXELIZE_GROUP_SIZE,
        rows: rows?,
    })
}

/// A cube of edge 0.8 inside the unit box, each face split into `n`×`n` quads (12·n²
/// triangles): the same surface at any `n`.
pub fn tessellated_cube(n: u32) -> (Vec<Vec3>, Vec<u32>) {
    let n = n.max(1);
    let (mut pos, mut idx) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        for side in [0.0f32, 1.0] {
            let base = pos.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    pos.push(Vec3::from(p) * 0.8 + 0.1);
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let a = base + j * (n + 1) + i;
                    idx.extend([a, a + 1, a + n + 1, a + 1, a + n + 2, a + n + 1]);
                }
            }
        }
    }
    (pos, idx)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dense_scene_fills_the_box_with_disjoint_bunnies() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        let s = dense_scene(&dir).expect("the dense scene builds");
        let n = DENSE_BUNNIES_PER_AXIS.pow(3) as usize;
        assert_eq!(s.objects.len(), n + 1, "walls and the bunnies");
        // Tight bounds of each object's transformed vertices.
        let bounds = |o: &crate::scene::Object| {
            let m = o.transform_at(0.0);
            let mesh = &s.meshes[o.mesh];
            mesh.positions
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                    let p = m.transform_point3(p);
                    (lo.min(p), hi.max(p))
                })
        };
        let walls = bounds(&s.objects[0]);
        let boxes: Vec<_> = s.objects[1..].iter().map(bounds).collect();
        for b in &boxes {
            assert!(
                b.0.cmpge(walls.0).all() && b.1.cmple(walls.1).all(),
                "{b:?}"
            );
        }
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                let overlap = a.0.cmplt(b.1).all() && b.0.cmplt(a.1).all();
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
        let tris =
            |s: &Scene| scene_triangles(s, 0.0, false).len() + scene_triangles(s, 0.0, true).len();
        assert_eq!(tris(&s), 235_146);
        let again = dense_scene(&dir).expect("builds again");
        assert_eq!(
            scene_triangles(&again, 0.0, false),
            scene_triangles(&s, 0.0, false),
            "deterministic"
        );
    }

    #[test]
    fn tessellated_cubes_share_one_surface() {
        let area = |n: u32| {
            let (p, idx) = tessellated_cube(n);
            idx.chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| p[t[k] as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum::<f32>()
        };
        assert_eq!(
            tessellated_cube(4).1.len() / 3,
            16 * tessellated_cube(1).1.len() / 3
        );
        assert!((area(1) - 6.0 * 0.64).abs() < 1e-4);
        assert!((area(4) - area(1)).abs() < 1e-4);
    }
}

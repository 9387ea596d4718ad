//! Casting batches of voxel-space rays on the GPU (`glsl/voxel_rays.comp`, built on the GLSL
//! traversal library `glsl/include/voxel_traverse.glsl`): the GPU side of the CPU-twin tests
//! and of `voxgi bench traverse`.
//!
//! The hierarchy travels in storage buffers with the CPU's exact level sizes (ceil halving),
//! so any grid size works and the GPU sees bit for bit what the CPU twin sees.

use super::bits::BitHierarchy;
use super::ray_mask::RayMaskLut;
use super::traverse::{HitResult, TraversalParams};
use crate::graph::{run_once, Access, GraphError, OneShotError, RenderGraph, Shader};
use crate::vk::{vk, Buffer, BufferDesc, ComputePipeline, Context, MemoryLocation, VkError};
use bytemuck::{Pod, Zeroable};
use glam::{UVec3, Vec3};

/// One ray of a batch (voxel space): origin and `t_max`, direction.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuRay {
    pub origin_tmax: [f32; 4],
    pub dir: [f32; 4],
}

impl GpuRay {
    pub fn new(origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self {
            origin_tmax: [origin.x, origin.y, origin.z, t_max],
            dir: [dir.x, dir.y, dir.z, 0.0],
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuRayResult {
    hit_voxel: [u32; 4],
    t_steps: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuRaysPush {
    /// Voxels (x, y, depth), max hierarchy level.
    dims: [i32; 4],
    start_level: u32,
    max_iterations: u32,
    /// 0 hierarchical, 1 exact DDA, 2 1-bit march, 3 3-bit march.
    mode: u32,
    ray_count: u32,
    marching_samples: u32,
    _pad: [u32; 3],
}

crate::push_constants!(GpuRaysPush {
    dims,
    start_level,
    max_iterations,
    mode,
    ray_count,
    marching_samples,
    _pad
});

/// Which ray test a batch uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayMethod {
    /// Hierarchical traversal with ray masks (Thiedemann 2010, §5.3.2).
    Hierarchical(TraversalParams),
    /// Exact voxel walk (ground truth).
    Dda,
    /// Uniform marching, 1-bit mask, this many samples (§6.4.1).
    March1(u32),
    /// Uniform marching, 3-bit mask, this many samples (§6.4.1).
    March3(u32),
}

impl RayMethod {
    pub fn name(&self) -> String {
        match self {
            RayMethod::Hierarchical(_) => "hierarchical".into(),
            RayMethod::Dda => "dda".into(),
            RayMethod::March1(n) => format!("march1x{n}"),
            RayMethod::March3(n) => format!("march3x{n}"),
        }
    }
}

/// Results of one batch: a hit per ray (positions are not read back) and the pass's GPU time.
#[derive(Clone, Debug)]
pub struct RayBatch {
    pub method: RayMethod,
    pub hits: Vec<HitResult>,
    /// Median of `gpu_ms_runs`.
    pub gpu_ms: f64,
    /// The pass's GPU time in each timed run.
    pub gpu_ms_runs: Vec<f64>,
    /// CPU time this process spent on each timed run of the method (its own submission),
    /// in ms, where the platform reports it (`/proc/self/task/*/schedstat`): on a CPU
    /// implementation of Vulkan (lavapipe) the work itself, and unlike wall-clock GPU time
    /// not stretched by other processes on a shared machine. Empty elsewhere.
    pub cpu_ms_runs: Vec<f64>,
}

/// CPU time of all threads of this process so far, in ns (`None` where `/proc` lacks it).
/// Threads that ended earlier are not counted, so only differences across a stretch in
/// which no thread ends mean anything.
pub fn process_cpu_ns() -> Option<u64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let path = task.ok()?.path().join("schedstat");
        let text = std::fs::read_to_string(path).ok()?;
        total += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total)
}

#[derive(Debug, thiserror::Error)]
pub enum RayCastError {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error("no rays to cast")]
    NoRays,
}

/// A voxel hierarchy on the GPU, ready to cast ray batches.
pub struct VoxelRayCaster {
    pipeline: ComputePipeline,
    columns: Buffer,
    levels: Buffer,
    lut: Buffer,
    dims: UVec3,
    max_level: u32,
}

impl VoxelRayCaster {
    pub fn new(ctx: &Context, h: &BitHierarchy) -> Result<Self, VkError> {
        let mut columns = Vec::new();
        let mut levels: Vec<[u32; 4]> = Vec::new();
        for l in 0..h.level_count() {
            let g = h.level(l);
            levels.push([(columns.len() / 16) as u32, g.res_x(), g.res_y(), 0]);
            columns.extend_from_slice(&g.to_gpu_bytes());
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let columns = ctx.upload_buffer("voxel columns", &columns, storage)?;
        let levels = ctx.upload_buffer("voxel levels", bytemuck::cast_slice(&levels), storage)?;
        let lut = ctx.upload_buffer("ray mask lut", &RayMaskLut::new().to_gpu_bytes(), storage)?;
        let pipeline = ctx.compute_pipeline(
            "voxel_rays.comp",
            crate::vk::PushLayout::of::<GpuRaysPush>(),
            &[],
        )?;
        let base = h.base();
        Ok(Self {
            pipeline,
            columns,
            levels,
            lut,
            dims: UVec3::new(base.res_x(), base.res_y(), base.depth()),
            max_level: h.max_level(),
        })
    }

    /// Casts `rays` once per method, side by side in one frame (one pass each), and returns
    /// every batch's hits and GPU time.
    pub fn cast(
        &self,
        ctx: &Context,
        rays: &[GpuRay],
        methods: &[RayMethod],
    ) -> Result<Vec<RayBatch>, RayCastError> {
        self.cast_timed(ctx, rays, methods, 1)
    }

    /// [`Self::cast`] timed over `runs` runs (one submission per method, the methods
    /// interleaved within each run, so a load that comes and goes on the machine touches
    /// each alike), after one untimed warm-up run when `runs > 1`. Every batch reports the
    /// median and each run's GPU time, and the CPU time of each run.
    pub fn cast_timed(
        &self,
        ctx: &Context,
        rays: &[GpuRay],
        methods: &[RayMethod],
        runs: u32,
    ) -> Result<Vec<RayBatch>, RayCastError> {
        if rays.is_empty() {
            return Err(RayCastError::NoRays);
        }
        let ray_buf = ctx.upload_buffer(
            "rays",
            bytemuck::cast_slice(rays),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        // The shader writes device-local memory and a copy pass reads it back: written
        // straight into host-visible memory, every test on a discrete GPU measured the bus
        // (about 15.7 ms for 3.9 M rays on an H200 whatever the method), not the traversal.
        let size_bytes = (rays.len() * std::mem::size_of::<GpuRayResult>()) as u64;
        let mut results = Vec::new();
        for m in methods {
            let device = ctx.create_buffer(&BufferDesc {
                name: format!("ray results {}", m.name()),
                size_bytes,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::GpuOnly,
            })?;
            let host = ctx.create_buffer(&BufferDesc {
                name: format!("ray results {} (read-back)", m.name()),
                size_bytes,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            })?;
            results.push(RayResults { device, host });
        }
        let count = rays.len() as u32;
        if runs > 1 {
            self.run(ctx, &ray_buf, &results, count, methods)?;
        }
        let mut gpu = vec![Vec::new(); methods.len()];
        let mut cpu = vec![Vec::new(); methods.len()];
        for _ in 0..runs.max(1) {
            for i in 0..methods.len() {
                let before = process_cpu_ns();
                let t = self.run(ctx, &ray_buf, &results[i..=i], count, &methods[i..=i])?;
                if let (Some(a), Some(b)) = (before, process_cpu_ns()) {
                    cpu[i].push(b.saturating_sub(a) as f64 * 1e-6);
                }
                gpu[i].extend(t);
            }
        }
        Ok(methods
            .iter()
            .zip(&results)
            .zip(gpu.into_iter().zip(cpu))
            .map(|((m, buf), (gpu_ms_runs, cpu_ms_runs))| RayBatch {
                method: *m,
                hits: read_hits(&buf.host, rays.len()),
                gpu_ms: crate::stats::median(&gpu_ms_runs),
                gpu_ms_runs,
                cpu_ms_runs,
            })
            .collect())
    }

    fn run(
        &self,
        ctx: &Context,
        rays: &Buffer,
        results: &[RayResults],
        count: u32,
        methods: &[RayMethod],
    ) -> Result<Vec<f64>, RayCastError> {
        let mut g = RenderGraph::new();
        let read = Access::StorageRead(Shader::Compute);
        let columns = g.import_buffer(&self.columns, read);
        let levels = g.import_buffer(&self.levels, read);
        let lut = g.import_buffer(&self.lut, read);
        let ray_h = g.import_buffer(rays, read);
        let pipe = *self.pipeline;
        let dims = [
            self.dims.x as i32,
            self.dims.y as i32,
            self.dims.z as i32,
            self.max_level as i32,
        ];
        for (i, (m, buf)) in methods.iter().zip(results).enumerate() {
            let out = g.import_buffer(&buf.device, Access::TransferRead);
            let host = g.import_buffer(&buf.host, Access::HostRead);
            let (mode, start_level, max_iterations, marching_samples) = match *m {
                RayMethod::Hierarchical(p) => (0, p.start_level, p.max_iterations, 0),
                RayMethod::Dda => (1, 0, 0, 0),
                RayMethod::March1(n) => (2, 0, 0, n),
                RayMethod::March3(n) => (3, 0, 0, n),
            };
            let push = GpuRaysPush {
                dims,
                start_level,
                max_iterations,
                mode,
                ray_count: count,
                marching_samples,
                _pad: [0; 3],
            };
            // The index keeps names unique when a method repeats with other settings.
            g.add_pass(&format!("voxel_rays[{i}: {}]", m.name()))
                .pipeline(&pipe)
                .bind(0, columns, read)
                .bind(1, levels, read)
                .bind(2, lut, read)
                .bind(3, ray_h, read)
                .bind(4, out, Access::StorageWrite(Shader::Compute))
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd.dispatch(count.div_ceil(64), 1, 1);
                });
            let size = buf.device.desc.size_bytes;
            g.add_pass(&format!("voxel_rays_readback[{i}]"))
                .read(out, Access::TransferRead)
                .write(host, Access::TransferWrite)
                .record(move |ctx| {
                    ctx.cmd
                        .copy_buffer(ctx.buffer(out).raw, ctx.buffer(host).raw, size)
                });
        }
        let timings = run_once(ctx, g).map_err(|e| match e {
            OneShotError::Graph(e) => RayCastError::Graph(e),
            OneShotError::Vk(e) => RayCastError::Vk(e),
        })?;
        // The ray passes' times alone; the read-back copies are not the ray test.
        Ok(timings
            .iter()
            .filter(|t| t.name.starts_with("voxel_rays["))
            .map(|t| t.gpu_ms)
            .collect())
    }
}

/// One method's hits: written by the shader into `device`, copied to `host` to be read.
struct RayResults {
    device: Buffer,
    host: Buffer,
}

fn read_hits(buf: &Buffer, n: usize) -> Vec<HitResult> {
    let Some(bytes) = buf.mapped() else {
        return Vec::new();
    };
    let results: &[GpuRayResult] =
        bytemuck::cast_slice(&bytes[..n * std::mem::size_of::<GpuRayResult>()]);
    results
        .iter()
        .map(|r| HitResult {
            hit: r.hit_voxel[0] != 0,
            voxel: UVec3::new(r.hit_voxel[1], r.hit_voxel[2], r.hit_voxel[3]),
            t: r.t_steps[0],
            position: Vec3::ZERO,
            steps: r.t_steps[1] as u32,
            ran_out: r.t_steps[2] != 0.0,
        })
        .collect()
}

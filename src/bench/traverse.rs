//! `voxgi bench traverse`: the speed comparison of Thiedemann 2010 (§9.3.1, Fig. 44/45) measured side
//! by side in one GPU run. Rays start at the camera-visible surface points of a scene (a
//! G-buffer traced on the CPU), offset along the normal (§5.3.1), cosine-distributed around it,
//! with a length limited by a radius. The hierarchical test, the exact voxel walk (a DDA, the
//! ground truth) and 1-bit and 3-bit marching (§6.4.1) cast the same rays.

use super::BenchError;
use crate::scene::Scene;
use crate::vk::Context;
use crate::voxel::gpu_rays::{GpuRay, RayMethod, VoxelRayCaster};
use crate::voxel::traverse::HitResult;
use crate::voxel::{voxelize_scene, BitGrid, BitHierarchy, GridDesc, TraversalParams, VoxelGrid};
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
    /// Marching sample counts to try (1-bit and 3-bit each); empty: no marching rows.
    pub march_steps: Vec<u32>,
    /// Normal offset, in voxel diagonals (thesis §5.3.1, k₁).
    pub normal_offset_voxels: f32,
    /// The hierarchical traversal's settings; the first is the reference of the agreement
    /// columns, the others are rows of their own (start levels side by side).
    pub params: Vec<TraversalParams>,
    /// Timed runs of every method (the median and the spread are reported), after one
    /// untimed warm-up run when more than 1.
    pub repeats: u32,
}

/// The default ray lengths, in the thesis's test-box units: a short, a middle and a long ray
/// (radius 8 crosses most of the scene).
pub const DEFAULT_RADII_BOX_UNITS: [f32; 3] = [2.0, 4.0, 8.0];

/// The default marching sample counts, doubling from 8 to 512 (the thesis's Fig. 44/45 range).
pub const DEFAULT_MARCH_STEPS: [u32; 7] = [8, 16, 32, 64, 128, 256, 512];

impl Default for TraverseBenchDesc {
    fn default() -> Self {
        Self {
            resolution: 128,
            gbuffer_size: 128,
            rays_per_point: 16,
            radii_box_units: DEFAULT_RADII_BOX_UNITS.to_vec(),
            march_steps: DEFAULT_MARCH_STEPS.to_vec(),
            normal_offset_voxels: 1.0,
            params: vec![TraversalParams::default()],
            repeats: 1,
        }
    }
}

/// One method at one radius.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    pub method: String,
    /// Marching samples per ray; `None` for the hierarchical test and the exact walk.
    pub samples: Option<u32>,
    /// Median GPU time over the runs, and the fastest and slowest run.
    pub gpu_ms: f64,
    pub gpu_ms_min: f64,
    pub gpu_ms_max: f64,
    /// Median CPU time of the process over the runs (lavapipe: the work itself, less
    /// disturbed by other load than the wall-clock GPU time); `None` where not measured.
    pub cpu_ms: Option<f64>,
    pub rays_per_s: f64,
    pub mean_steps: f64,
    /// Share of rays this test reports a hit on.
    pub hit_fraction: f64,
    /// Share of rays whose hit/miss agrees with the hierarchical test.
    pub agreement: f64,
    /// Share of rays whose hit/miss agrees with the exact voxel walk (the ground truth).
    pub exact_agreement: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct RadiusResult {
    pub radius_box_units: f32,
    pub radius_m: f32,
    pub rays: usize,
    pub hit_fraction: f64,
    pub methods: Vec<MethodResult>,
    /// Fewest marching samples whose results agree with the hierarchical test on ≥ 99% of
    /// rays, if any tried count does ([`fewest_samples_at_99`]).
    pub march_steps_for_99: Option<u32>,
    /// GPU time of that marching run divided by the hierarchical test's.
    pub speedup_at_99: Option<f64>,
    /// The same for 3-bit marching (Thiedemann 2010 §6.4.1: three bits per sample, one per
    /// axis-aligned neighbour, so a thin wall crossed between samples is still seen).
    pub march3_steps_for_99: Option<u32>,
    pub march3_speedup_at_99: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct TraverseBenchReport {
    pub device: String,
    pub grid: [u32; 3],
    pub points: usize,
    pub radii: Vec<RadiusResult>,
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
    let mut out = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let (near, far) = scene.camera.pixel_ray_points(x, y, size, size);
            let o = scene.camera.position;
            let d = (far - near).normalize();
            let mut best: Option<(f32, usize)> = None;
            for (i, t) in tris.iter().enumerate() {
                if let Some(dist) = intersect(o, d, t) {
                    if best.is_none_or(|(b, _)| dist < b) {
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

/// The benchmark's rays on `scene`: the hierarchy of the scene's voxelization and, per radius
/// of `desc`, the voxel-space rays from the camera-visible surface points.
pub struct TraverseRays {
    pub hierarchy: BitHierarchy,
    /// Camera-visible surface points the rays start from.
    pub points: usize,
    /// `(radius in box units, radius in meters, rays)` per radius of the description.
    pub radii: Vec<(f32, f32, Vec<GpuRay>)>,
}

/// Voxelizes `scene` and casts the benchmark's rays (no GPU work).
pub fn traverse_rays(scene: &Scene, desc: &TraverseBenchDesc) -> Result<TraverseRays, BenchError> {
    if let Some(&radius) = desc
        .radii_box_units
        .iter()
        .find(|r| !(r.is_finite() && **r > 0.0))
    {
        return Err(BenchError::TraverseRadius { radius });
    }
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
    let hierarchy = BitHierarchy::build(bits);
    let points = gbuffer_points(scene, desc.gbuffer_size);
    if points.is_empty() {
        return Err(BenchError::NoSurface);
    }
    let offset = desc.normal_offset_voxels * grid.voxel_diagonal_m();
    let scene_size = aabb.extent().max_element();
    let mut radii = Vec::new();
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
        radii.push((r, radius_m, rays));
    }
    Ok(TraverseRays {
        hierarchy,
        points: points.len(),
        radii,
    })
}

/// Runs the benchmark on `scene`.
pub fn bench_traverse(
    ctx: &Context,
    scene: &Scene,
    desc: &TraverseBenchDesc,
) -> Result<TraverseBenchReport, BenchError> {
    let setup = traverse_rays(scene, desc)?;
    let caster = VoxelRayCaster::new(ctx, &setup.hierarchy)?;
    let radii = setup
        .radii
        .iter()
        .map(|(r, radius_m, rays)| bench_radius(ctx, &caster, desc, *r, *radius_m, rays))
        .collect::<Result<Vec<_>, _>>()?;
    let b = setup.hierarchy.base();
    Ok(TraverseBenchReport {
        device: ctx.info.name.clone(),
        grid: [b.res_x(), b.res_y(), b.depth()],
        points: setup.points,
        radii,
    })
}

/// The fewest marching samples whose hit/miss agrees with the reference on at least 99% of
/// the rays, and how many times the hierarchical test is faster than that marching: of
/// `(samples, agreement, ms)` per marching run and the hierarchical test's ms in the same run.
/// `None` when no run reaches 99%.
pub fn fewest_samples_at_99(
    runs: impl IntoIterator<Item = (u32, f64, f64)>,
    hierarchical_ms: f64,
) -> Option<(u32, f64)> {
    runs.into_iter()
        .filter(|&(_, agreement, _)| agreement >= 0.99)
        .min_by_key(|&(samples, _, _)| samples)
        .map(|(samples, _, ms)| (samples, ms / hierarchical_ms.max(1e-9)))
}

/// One radius of the benchmark: the hierarchical test (each of `desc.params`), the exact walk
/// and every marching sample count of `desc` cast on `rays`, interleaved over
/// `desc.repeats` runs (`radius`: in box units and in meters, for the report).
pub fn bench_radius(
    ctx: &Context,
    caster: &VoxelRayCaster,
    desc: &TraverseBenchDesc,
    radius_box_units: f32,
    radius_m: f32,
    rays: &[GpuRay],
) -> Result<RadiusResult, BenchError> {
    let Some(&first) = desc.params.first() else {
        return Err(BenchError::NoHierarchicalParams);
    };
    let mut methods = vec![RayMethod::Hierarchical(first), RayMethod::Dda];
    methods.extend(desc.params[1..].iter().map(|&p| RayMethod::Hierarchical(p)));
    methods.extend(desc.march_steps.iter().map(|&s| RayMethod::March1(s)));
    methods.extend(desc.march_steps.iter().map(|&s| RayMethod::March3(s)));
    let batches = caster.cast_timed(ctx, rays, &methods, desc.repeats)?;
    let several = desc.params.len() > 1;
    let (reference, exact) = (&batches[0], &batches[1]);
    let n = rays.len() as f64;
    let hit_share = |a: &[HitResult]| a.iter().filter(|h| h.hit).count() as f64 / n;
    let share = |a: &[HitResult], b: &[HitResult]| {
        a.iter().zip(b).filter(|(x, y)| x.hit == y.hit).count() as f64 / n
    };
    let mut results = Vec::new();
    for b in &batches {
        let method = match b.method {
            RayMethod::Hierarchical(p) if several => format!("hierarchical/{}", p.start_level),
            m => m.name(),
        };
        let runs = &b.gpu_ms_runs;
        results.push(MethodResult {
            method,
            samples: match b.method {
                RayMethod::March1(s) | RayMethod::March3(s) => Some(s),
                _ => None,
            },
            gpu_ms: b.gpu_ms,
            gpu_ms_min: runs.iter().copied().fold(f64::INFINITY, f64::min),
            gpu_ms_max: runs.iter().copied().fold(0.0, f64::max),
            cpu_ms: (!b.cpu_ms_runs.is_empty()).then(|| crate::stats::median(&b.cpu_ms_runs)),
            rays_per_s: n / (b.gpu_ms.max(1e-9) * 1e-3),
            mean_steps: b.hits.iter().map(|h| f64::from(h.steps)).sum::<f64>() / n,
            hit_fraction: hit_share(&b.hits),
            agreement: share(&b.hits, &reference.hits),
            exact_agreement: share(&b.hits, &exact.hits),
        });
    }
    let at_99 = |bits: u32| {
        let runs = batches
            .iter()
            .zip(&results)
            .filter_map(|(b, m)| match b.method {
                RayMethod::March1(s) if bits == 1 => Some((s, m.agreement, b.gpu_ms)),
                RayMethod::March3(s) if bits == 3 => Some((s, m.agreement, b.gpu_ms)),
                _ => None,
            });
        fewest_samples_at_99(runs, reference.gpu_ms)
    };
    let (march1_99, march3_99) = (at_99(1), at_99(3));
    Ok(RadiusResult {
        radius_box_units,
        radius_m,
        rays: rays.len(),
        hit_fraction: hit_share(&reference.hits),
        methods: results,
        march_steps_for_99: march1_99.map(|(s, _)| s),
        speedup_at_99: march1_99.map(|(_, x)| x),
        march3_steps_for_99: march3_99.map(|(s, _)| s),
        march3_speedup_at_99: march3_99.map(|(_, x)| x),
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
                "  {:<16} {:>10} {:>17} {:>10} {:>10} {:>10} {:>10} {:>10}\n",
                "method",
                "GPU ms",
                "min-max",
                "CPU ms",
                "Mrays/s",
                "steps/ray",
                "agree %",
                "exact %"
            );
            for m in &r.methods {
                s += &format!(
                    "  {:<16} {:>10.3} {:>17} {:>10} {:>10.2} {:>10.2} {:>10.2} {:>10.2}\n",
                    m.method,
                    m.gpu_ms,
                    format!("{:.2}-{:.2}", m.gpu_ms_min, m.gpu_ms_max),
                    m.cpu_ms.map_or("-".into(), |c| format!("{c:.1}")),
                    m.rays_per_s * 1e-6,
                    m.mean_steps,
                    100.0 * m.agreement,
                    100.0 * m.exact_agreement
                );
            }
            let marching = r.methods.iter().any(|m| m.method.starts_with("march"));
            for (bits, steps, speedup) in [
                (1, r.march_steps_for_99, r.speedup_at_99),
                (3, r.march3_steps_for_99, r.march3_speedup_at_99),
            ] {
                match (steps, speedup) {
                    _ if !marching => {}
                    (Some(n), Some(x)) => {
                        s += &format!("  {bits}-bit marching needs {n} samples to agree on >= 99% of rays; hierarchical is {x:.2}x faster than that\n")
                    }
                    _ => s += &format!("  no tried {bits}-bit marching sample count agrees on >= 99% of rays\n"),
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fewest_samples_at_99_percent_are_chosen_whatever_the_order() {
        // (samples, agreement, ms); the hierarchical test took 2 ms.
        let runs = [
            (128, 0.999, 12.0),
            (16, 0.95, 3.0),
            (64, 0.99, 8.0),
            (32, 0.989, 5.0),
        ];
        // 64 is the fewest at >= 99% (exactly 0.99 counts); 8 ms / 2 ms = 4x.
        assert_eq!(fewest_samples_at_99(runs, 2.0), Some((64, 4.0)));
        assert_eq!(fewest_samples_at_99(runs[1..2].iter().copied(), 2.0), None);
        assert_eq!(fewest_samples_at_99([], 2.0), None);
    }
}

//! The GLSL hierarchical ray test against its CPU twin (bit for bit) and against the exact
//! voxel walk, on random grids, the Cornell box and the bunny, plus extreme rays. Validation
//! and synchronization validation on.

mod common;

use glam::Vec3;
use voxgi::voxel::gpu_rays::{GpuRay, RayMethod, VoxelRayCaster};
use voxgi::voxel::traverse::{first_hit_dda, first_hit_hierarchical, march_1bit, march_3bit};
use voxgi::voxel::{
    voxelize_scene, BitGrid, BitHierarchy, GridDesc, HitResult, TraversalParams, VoxelGrid,
};

/// SplitMix64: a tiny deterministic generator (no test should depend on a seed it can't print).
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn random_grid(rng: &mut Rng, x: u32, y: u32, layers: u32, density: f32) -> BitHierarchy {
    let mut g = BitGrid::new(x, y, layers);
    for k in 0..128 * layers {
        for j in 0..y {
            for i in 0..x {
                if rng.f() < density {
                    g.set(i, j, k);
                }
            }
        }
    }
    BitHierarchy::build(g)
}

/// Rays from random points in and around the grid to random points, with a share of
/// axis-aligned, face-diagonal and tiny-component directions and integer (voxel-face) origins.
fn random_rays(rng: &mut Rng, dims: Vec3, n: usize) -> Vec<GpuRay> {
    (0..n)
        .map(|i| {
            let mut o = Vec3::new(rng.f(), rng.f(), rng.f()) * dims * 1.4 - dims * 0.2;
            if i % 5 == 0 {
                o = o.round();
            }
            let mut d = Vec3::new(rng.f() - 0.5, rng.f() - 0.5, rng.f() - 0.5);
            match i % 11 {
                0 => d = Vec3::new(d.x.signum(), 0.0, 0.0),
                1 => d = Vec3::new(0.0, 0.0, d.z.signum()),
                2 => d = Vec3::new(d.x.signum(), d.y.signum(), 0.0),
                3 => d.y = 1e-30,
                4 => d = Vec3::new(d.x.signum(), -d.x.signum(), d.z.signum()),
                _ => {}
            }
            let t_max = if i % 7 == 0 {
                f32::INFINITY
            } else {
                rng.f() * dims.max_element() * 1.5
            };
            GpuRay::new(o, d, t_max)
        })
        .collect()
}

fn same(a: &HitResult, b: &HitResult) -> bool {
    a.hit == b.hit
        && a.ran_out == b.ran_out
        && a.steps == b.steps
        && (!a.hit || (a.voxel == b.voxel && a.t.to_bits() == b.t.to_bits()))
}

/// Casts `rays` on the GPU (hierarchical and DDA) and checks them against the CPU twin and
/// the DDA; returns (rays that ran out of iterations, rays that hit).
fn check(
    ctx: &voxgi::vk::Context,
    h: &BitHierarchy,
    rays: &[GpuRay],
    what: &str,
) -> (usize, usize) {
    let params = TraversalParams {
        start_level: 1,
        max_iterations: 4096,
    };
    let caster = VoxelRayCaster::new(ctx, h).expect("uploads the hierarchy");
    let batches = caster
        .cast(
            ctx,
            rays,
            &[RayMethod::Hierarchical(params), RayMethod::Dda],
        )
        .expect("casts");
    let (gpu_h, gpu_dda) = (&batches[0].hits, &batches[1].hits);
    let mut ran_out = 0;
    let hits = gpu_h.iter().filter(|h| h.hit).count();
    for (i, r) in rays.iter().enumerate() {
        let (o, d, t) = (
            Vec3::from_slice(&r.origin_tmax[..3]),
            Vec3::from_slice(&r.dir[..3]),
            r.origin_tmax[3],
        );
        let cpu = first_hit_hierarchical(h, o, d, t, &params);
        assert!(
            same(&gpu_h[i], &cpu),
            "{what}: ray {i} ({o}, {d}, {t}): GPU {:?} != CPU {:?}",
            gpu_h[i],
            cpu
        );
        let dda = first_hit_dda(h.base(), o, d, t);
        assert!(
            same_hit(&gpu_dda[i], &dda),
            "{what}: ray {i}: GPU DDA {:?} != CPU DDA {:?}",
            gpu_dda[i],
            dda
        );
        if cpu.ran_out {
            ran_out += 1;
        } else {
            assert!(
                same_hit(&cpu, &dda),
                "{what}: ray {i}: hierarchical {cpu:?} != DDA {dda:?}"
            );
        }
    }
    (ran_out, hits)
}

/// Same first hit (voxel and t), ignoring step counts.
fn same_hit(a: &HitResult, b: &HitResult) -> bool {
    a.hit == b.hit && (!a.hit || (a.voxel == b.voxel && a.t.to_bits() == b.t.to_bits()))
}

#[test]
fn gpu_traversal_matches_cpu_twin_on_random_grids() {
    let ctx = common::context();
    let mut rng = Rng(7);
    for (x, y, layers, density) in [
        (64, 48, 1, 0.01),
        (64, 48, 1, 0.1),
        (32, 32, 2, 0.3),
        (1, 1, 1, 0.2),
        (37, 5, 2, 0.05),
    ] {
        let h = random_grid(&mut rng, x, y, layers, density);
        let dims = Vec3::new(x as f32, y as f32, (128 * layers) as f32);
        let rays = random_rays(&mut rng, dims, 100_000);
        let (ran_out, hits) = check(
            &ctx,
            &h,
            &rays,
            &format!("{x}x{y}x{} density {density}", 128 * layers),
        );
        assert_eq!(ran_out, 0, "{x}x{y}: {ran_out} rays ran out of iterations");
        assert!(
            hits > rays.len() / 20,
            "{x}x{y} density {density}: only {hits} rays hit; the comparison would be vacuous"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

fn scene_grid(scene: &voxgi::scene::Scene, res: u32) -> BitHierarchy {
    let aabb = scene.aabb_at(0.0);
    let grid = VoxelGrid::around(
        aabb.min,
        aabb.max,
        &GridDesc {
            max_res_xy: res,
            ..Default::default()
        },
    )
    .expect("grid");
    let mut bits = BitGrid::for_grid(&grid);
    voxelize_scene(&grid, &mut bits, scene, 0.0).expect("voxelizes");
    BitHierarchy::build(bits)
}

#[test]
fn gpu_traversal_matches_cpu_twin_on_cornell_and_bunny() {
    let ctx = common::context();
    let mut rng = Rng(11);
    let cornell = voxgi::scene::builtin("cornell").expect("cornell");
    let bunny_path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenes/cornell_bunny.toml"
    );
    let bunny = voxgi::scene::Scene::load(bunny_path).expect("bunny scene");
    for (name, scene) in [("cornell", &cornell), ("bunny", &bunny)] {
        let h = scene_grid(scene, 128);
        assert!(
            h.base().count_ones() > 1000,
            "{name} voxelizes to something"
        );
        let b = h.base();
        let dims = Vec3::new(b.res_x() as f32, b.res_y() as f32, b.depth() as f32);
        let rays = random_rays(&mut rng, dims, 100_000);
        let (ran_out, hits) = check(&ctx, &h, &rays, name);
        assert_eq!(ran_out, 0, "{name}: {ran_out} rays ran out of iterations");
        assert!(
            hits > rays.len() / 20,
            "{name}: only {hits} rays hit; the comparison would be vacuous"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn gpu_extreme_rays_match_cpu() {
    let ctx = common::context();
    let mut rng = Rng(3);
    let h = random_grid(&mut rng, 16, 16, 2, 0.05);
    let mut rays = Vec::new();
    let axes = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    for o in [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(8.0, 8.0, 64.0),
        Vec3::new(7.5, 3.0, 100.0),
        Vec3::new(16.0, 16.0, 256.0),
    ] {
        for d in axes {
            rays.push(GpuRay::new(o, d, f32::INFINITY));
        }
        for d in [
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1e-30, 1.0, -1e-30),
            Vec3::new(0.0, 1e-30, 1.0),
        ] {
            rays.push(GpuRay::new(o, d, f32::INFINITY));
            rays.push(GpuRay::new(o, -d, 40.0));
        }
        rays.push(GpuRay::new(o, Vec3::ZERO, 1.0)); // zero direction: a point query
        rays.push(GpuRay::new(o, Vec3::X, 0.0)); // zero length
    }
    rays.push(GpuRay::new(
        Vec3::new(-1e30, 4.0, 4.0),
        Vec3::X,
        f32::INFINITY,
    )); // from far outside
    rays.push(GpuRay::new(
        Vec3::new(-5.0, -5.0, -5.0),
        Vec3::NEG_X,
        f32::INFINITY,
    )); // missing
    rays.push(GpuRay::new(
        Vec3::new(4.0, 4.0, 4.0),
        Vec3::new(f32::NAN, 0.0, 1.0),
        1.0,
    )); // NaN: miss
    check(&ctx, &h, &rays, "extremes");
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn gpu_segment_visibility_matches_cpu_visible() {
    // voxel_visible(a, b) is voxel_first_hit(a, b - a, t_max = 1): cast segments and compare
    // with the CPU twin's `visible` on every segment.
    use voxgi::voxel::traverse::visible;
    let ctx = common::context();
    let mut rng = Rng(23);
    let h = random_grid(&mut rng, 48, 40, 2, 0.01);
    let dims = Vec3::new(48.0, 40.0, 256.0);
    let segments: Vec<(Vec3, Vec3)> = (0..50_000)
        .map(|_| {
            (
                Vec3::new(rng.f(), rng.f(), rng.f()) * dims,
                Vec3::new(rng.f(), rng.f(), rng.f()) * dims,
            )
        })
        .collect();
    let rays: Vec<GpuRay> = segments
        .iter()
        .map(|&(a, b)| GpuRay::new(a, b - a, 1.0))
        .collect();
    let params = TraversalParams {
        start_level: 1,
        max_iterations: 4096,
    };
    let caster = VoxelRayCaster::new(&ctx, &h).expect("uploads");
    let batch = caster
        .cast(&ctx, &rays, &[RayMethod::Hierarchical(params)])
        .expect("casts");
    let mut blocked = 0;
    for (i, &(a, b)) in segments.iter().enumerate() {
        let gpu_visible = !batch[0].hits[i].hit;
        assert_eq!(
            gpu_visible,
            visible(&h, a, b, &params),
            "segment {i}: {a} -> {b}"
        );
        blocked += usize::from(!gpu_visible);
    }
    assert!(
        blocked > 1000 && blocked < 49_000,
        "{blocked} of 50000 segments blocked: both outcomes are exercised"
    );
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn gpu_marching_baselines_match_cpu() {
    let ctx = common::context();
    let mut rng = Rng(5);
    let h = random_grid(&mut rng, 32, 24, 1, 0.02);
    let rays = random_rays(&mut rng, Vec3::new(32.0, 24.0, 128.0), 20_000);
    let caster = VoxelRayCaster::new(&ctx, &h).expect("uploads");
    let batches = caster
        .cast(&ctx, &rays, &[RayMethod::March1(40), RayMethod::March3(40)])
        .expect("casts");
    for (i, r) in rays.iter().enumerate() {
        let (o, d, t) = (
            Vec3::from_slice(&r.origin_tmax[..3]),
            Vec3::from_slice(&r.dir[..3]),
            r.origin_tmax[3],
        );
        let m1 = march_1bit(h.base(), o, d, t, 40);
        let m3 = march_3bit(h.base(), o, d, t, 40);
        assert!(
            same(&batches[0].hits[i], &m1),
            "ray {i}: 1-bit GPU {:?} != CPU {m1:?}",
            batches[0].hits[i]
        );
        assert!(
            same(&batches[1].hits[i], &m3),
            "ray {i}: 3-bit GPU {:?} != CPU {m3:?}",
            batches[1].hits[i]
        );
    }
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn gpu_traversal_on_a_512_cubed_grid() {
    let ctx = common::context();
    let mut rng = Rng(17);
    let mut g = BitGrid::new(512, 512, 4);
    // Sparse random voxels plus a few solid slabs, so rays both travel far and stop.
    for _ in 0..200_000 {
        let v = (
            rng.next_u64() % 512,
            rng.next_u64() % 512,
            rng.next_u64() % 512,
        );
        g.set(v.0 as u32, v.1 as u32, v.2 as u32);
    }
    for i in 0..512 {
        for j in 0..512 {
            g.set(i, j, 300);
            g.set(400, i, j);
        }
    }
    let h = BitHierarchy::build(g);
    let rays = random_rays(&mut rng, Vec3::splat(512.0), 20_000);
    let (ran_out, hits) = check(&ctx, &h, &rays, "512^3");
    assert_eq!(ran_out, 0, "512^3: {ran_out} rays ran out of iterations");
    assert!(hits > rays.len() / 20, "512^3: only {hits} hits");
    common::assert_no_validation_messages(&ctx);
}

//! Tests of the ray queries: hierarchical == DDA on random grids and rays, the DDA against an
//! independent f64 brute force, and the numerical extremes listed in the README's
//! Tests section.

use glam::{DVec3, UVec3, Vec3};

use super::bits::{BitGrid, BitHierarchy};
use super::grid::{Axis, VoxelGrid};
use super::traverse::{
    first_hit_dda, first_hit_hierarchical, march_1bit, march_3bit, visible, HitResult,
    TraversalParams,
};

/// Small deterministic generator (tests must not depend on a registry crate's stream).
struct Rng(u64);

impl Rng {
    fn u64(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn f32(&mut self) -> f32 {
        (self.u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.u64() % u64::from(n.max(1))) as u32
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

const GENEROUS: TraversalParams = TraversalParams {
    start_level: 1,
    max_iterations: 1_000_000,
};

/// Random grid: independent bits of density `p` plus a few axis-aligned walls and random
/// blobs, so the hierarchy has both empty space and structure.
fn random_grid(rng: &mut Rng, w: u32, h: u32, layers: u32, p: f32) -> BitGrid {
    let mut g = BitGrid::new(w, h, layers);
    let d = g.depth();
    for y in 0..h {
        for x in 0..w {
            for k in 0..d {
                if rng.f32() < p {
                    g.set(x, y, k);
                }
            }
        }
    }
    for _ in 0..rng.below(3) {
        // A partial wall perpendicular to a random axis.
        let axis = rng.below(3);
        let at = rng.below([w, h, d][axis as usize]);
        for y in 0..h {
            for x in 0..w {
                for k in 0..d {
                    let c = [x, y, k][axis as usize];
                    if c == at && rng.f32() < 0.7 {
                        g.set(x, y, k);
                    }
                }
            }
        }
    }
    g
}

/// Random ray: origins inside and around the grid, often on voxel corners, edges and faces;
/// directions random, axis-aligned, face-diagonal, or with zero / ±1e-30 / grazing parts.
fn random_ray(rng: &mut Rng, dims: UVec3) -> (Vec3, Vec3, f32) {
    let dims_f = dims.as_vec3();
    let mut o = Vec3::new(
        rng.range(-0.2, 1.2) * dims_f.x,
        rng.range(-0.2, 1.2) * dims_f.y,
        rng.range(-0.2, 1.2) * dims_f.z,
    );
    match rng.below(6) {
        0 => o = o.round(),
        1 => o.x = o.x.round(),
        2 => o = o.floor() + 0.5,
        _ => {}
    }
    let mut d = rng.unit();
    match rng.below(10) {
        0 => {
            d = Vec3::ZERO;
            d[rng.below(3) as usize] = if rng.below(2) == 0 { 1.0 } else { -1.0 };
        }
        1 => {
            d = Vec3::new(
                rng.below(3) as f32 - 1.0,
                rng.below(3) as f32 - 1.0,
                rng.below(3) as f32 - 1.0,
            );
        }
        2 => d[rng.below(3) as usize] = [0.0, 1e-30, -1e-30, 1e-7, -1e-6][rng.below(5) as usize],
        3 => d *= 1e-3,
        _ => {}
    }
    let t_max = if rng.below(2) == 0 {
        f32::INFINITY
    } else {
        rng.range(0.0, 2.0) * dims_f.length() / d.length().max(1e-3)
    };
    (o, d, t_max)
}

/// Hierarchical vs DDA on `rays` random rays; returns (ran_out count, hits).
fn compare_on(rng: &mut Rng, bits: &BitGrid, rays: u32) -> (u32, u32) {
    let h = BitHierarchy::build(bits.clone());
    let dims = UVec3::new(bits.res_x(), bits.res_y(), bits.depth());
    let (mut ran_out, mut hits) = (0, 0);
    for _ in 0..rays {
        let (o, d, t_max) = random_ray(rng, dims);
        let params = TraversalParams {
            start_level: rng.below(h.level_count() + 1),
            ..GENEROUS
        };
        let a = first_hit_hierarchical(&h, o, d, t_max, &params);
        let b = first_hit_dda(bits, o, d, t_max);
        if a.ran_out {
            ran_out += 1;
            continue;
        }
        assert_eq!(
            (a.hit, a.voxel, a.t.to_bits()),
            (b.hit, b.voxel, b.t.to_bits()),
            "o={o:?} d={d:?} t_max={t_max} dims={dims} hier={a:?} dda={b:?}"
        );
        assert!(!a.position.is_nan() && !a.t.is_nan());
        hits += u32::from(a.hit);
    }
    (ran_out, hits)
}

#[test]
fn hierarchical_equals_dda_on_random_grids() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut total_ran_out = 0;
    let mut rays = 0;
    // (res_x, res_y, layers): square, odd sizes, 2 layers (D = 256), 1×1×128, thin strips.
    let shapes = [
        (16, 16, 1),
        (33, 17, 1),
        (8, 8, 2),
        (1, 1, 1),
        (64, 3, 1),
        (5, 40, 2),
    ];
    for &(w, h, l) in &shapes {
        for &p in &[0.0005f32, 0.005, 0.05, 0.3] {
            let bits = random_grid(&mut rng, w, h, l, p);
            let (ran_out, _) = compare_on(&mut rng, &bits, 900);
            total_ran_out += ran_out;
            rays += 900;
        }
    }
    assert!(rays >= 20_000);
    assert_eq!(total_ran_out, 0, "rays that ran out of iterations");
}

#[test]
fn visibility_equals_dda_visibility() {
    let mut rng = Rng(77);
    let mut asymmetric = 0;
    for &(w, h, l) in &[(16u32, 16u32, 1u32), (7, 9, 2), (1, 1, 1)] {
        let bits = random_grid(&mut rng, w, h, l, 0.01);
        let hier = BitHierarchy::build(bits.clone());
        let dims = UVec3::new(w, h, 128 * l).as_vec3();
        for _ in 0..1500 {
            let a = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * dims * 1.2 - 0.1 * dims;
            let mut b = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * dims * 1.2 - 0.1 * dims;
            if rng.below(8) == 0 {
                b = a; // zero-length segment
            }
            let want = !first_hit_dda(&bits, a, b - a, 1.0).hit;
            assert_eq!(visible(&hier, a, b, &GENEROUS), want, "{a} -> {b}");
            let back = !first_hit_dda(&bits, b, a - b, 1.0).hit;
            assert_eq!(visible(&hier, b, a, &GENEROUS), back, "{b} -> {a}");
            // The visited point set does not depend on the direction; only f32 rounding of a
            // near-tie (seen ~1 in 10^6 random segments) can make the two disagree.
            asymmetric += u32::from(want != back);
        }
    }
    assert!(
        asymmetric <= 1,
        "{asymmetric} segments changed visibility when reversed"
    );
}

/// Closed-box ray interval in f64, box grown by `grow` (negative shrinks).
fn ray_box(o: DVec3, d: DVec3, t_max: f64, lo: DVec3, hi: DVec3, grow: f64) -> Option<f64> {
    let (lo, hi) = (lo - grow, hi + grow);
    let (mut t0, mut t1) = (0.0f64, t_max);
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < lo[i] || o[i] > hi[i] {
                return None;
            }
        } else {
            let (a, b) = ((lo[i] - o[i]) / d[i], (hi[i] - o[i]) / d[i]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    (t0 <= t1).then_some(t0)
}

#[test]
fn dda_matches_f64_brute_force() {
    let mut rng = Rng(4242);
    let tol = 1e-4;
    for &(w, h, l, p) in &[
        (6u32, 5u32, 1u32, 0.01f32),
        (4, 4, 2, 0.003),
        (1, 1, 1, 0.05),
    ] {
        let bits = random_grid(&mut rng, w, h, l, p);
        let set: Vec<DVec3> = (0..bits.depth())
            .flat_map(|k| (0..h).flat_map(move |y| (0..w).map(move |x| UVec3::new(x, y, k))))
            .filter(|v| bits.get(v.x, v.y, v.z))
            .map(|v| v.as_dvec3())
            .collect();
        let dims = UVec3::new(w, h, bits.depth()).as_vec3();
        for _ in 0..1000 {
            let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * dims * 1.4 - 0.2 * dims;
            let d = rng.unit();
            let t_max = if rng.below(2) == 0 {
                f32::INFINITY
            } else {
                rng.range(0.0, 200.0)
            };
            let r = first_hit_dda(&bits, o, d, t_max);
            let (o64, d64, tm) = (o.as_dvec3(), d.as_dvec3(), f64::from(t_max));
            // Earliest entry into any set voxel, boxes shrunk: the DDA may not miss it.
            let earliest = set
                .iter()
                .filter_map(|&v| ray_box(o64, d64, tm, v, v + 1.0, -tol))
                .fold(f64::INFINITY, f64::min);
            if r.hit {
                let v = r.voxel.as_dvec3();
                assert!(
                    ray_box(o64, d64, tm, v, v + 1.0, tol).is_some(),
                    "DDA hit a voxel the ray misses: {r:?} o={o} d={d}"
                );
                if let Some(tv) = ray_box(o64, d64, tm, v, v + 1.0, 0.0) {
                    assert!((tv - f64::from(r.t)).abs() < 1e-3, "{tv} vs {r:?}");
                }
                assert!(
                    f64::from(r.t) <= earliest + 1e-3,
                    "DDA skipped a voxel: {r:?} o={o} d={d}"
                );
            } else {
                assert!(
                    earliest.is_infinite(),
                    "DDA missed a voxel at t={earliest}: o={o} d={d}"
                );
            }
        }
    }
}

fn both(bits: &BitGrid, o: Vec3, d: Vec3, t_max: f32) -> HitResult {
    let h = BitHierarchy::build(bits.clone());
    let a = first_hit_hierarchical(&h, o, d, t_max, &GENEROUS);
    let b = first_hit_dda(bits, o, d, t_max);
    assert_eq!((a.hit, a.voxel, a.t), (b.hit, b.voxel, b.t), "o={o} d={d}");
    assert!(!a.ran_out);
    a
}

#[test]
fn axis_parallel_and_diagonal_rays() {
    let mut bits = BitGrid::new(8, 8, 2);
    bits.set(3, 4, 200);
    bits.set(5, 5, 5);
    bits.set(6, 6, 6);
    // +z through the column from the near plane, from inside, and starting on a face.
    for z0 in [0.0, 17.3, 200.0, 199.999] {
        let r = both(&bits, Vec3::new(3.5, 4.5, z0), Vec3::Z, f32::INFINITY);
        assert!(r.hit && r.voxel == UVec3::new(3, 4, 200));
        assert_eq!(r.t, (200.0 - z0).max(0.0));
    }
    // −z from the far side.
    let r = both(&bits, Vec3::new(3.5, 4.5, 256.0), -Vec3::Z, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(3, 4, 200) && r.t == 55.0);
    // Along a voxel edge: x = 3.0, y = 4.0 lies in voxel (3, 4) by the half-open rule.
    let r = both(&bits, Vec3::new(3.0, 4.0, 0.0), Vec3::Z, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(3, 4, 200));
    // On the upper face of the grid (x = 8) a parallel ray is outside.
    assert!(!both(&bits, Vec3::new(8.0, 4.5, 0.0), Vec3::Z, f32::INFINITY).hit);
    // ±x, ±y.
    let r = both(&bits, Vec3::new(0.0, 5.5, 5.5), Vec3::X, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(5, 5, 5) && r.t == 5.0);
    let r = both(&bits, Vec3::new(5.5, 8.0, 5.5), -Vec3::Y, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(5, 5, 5) && r.t == 2.0);
    // Space diagonal through voxel corners: (5,5,5) and (6,6,6) lie on it.
    let r = both(&bits, Vec3::ZERO, Vec3::ONE, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(5, 5, 5) && r.t == 5.0);
    let r = both(&bits, Vec3::splat(8.0), -Vec3::ONE, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(6, 6, 6) && r.t == 1.0);
    // Face diagonal exactly through the edge shared by four columns: the side columns are
    // touched only along a line and are not visited.
    let mut edge = BitGrid::new(4, 4, 1);
    edge.set(2, 1, 10);
    edge.set(1, 2, 10);
    let r = both(
        &edge,
        Vec3::new(0.0, 0.0, 10.5),
        Vec3::new(1.0, 1.0, 0.0),
        f32::INFINITY,
    );
    assert!(!r.hit);
    edge.set(2, 2, 10);
    let r = both(
        &edge,
        Vec3::new(0.0, 0.0, 10.5),
        Vec3::new(1.0, 1.0, 0.0),
        f32::INFINITY,
    );
    assert!(r.hit && r.voxel == UVec3::new(2, 2, 10) && r.t == 2.0);
    // t_max stops short of the voxel; t_max reaching exactly its face includes it.
    assert!(!both(&bits, Vec3::new(0.0, 5.5, 5.5), Vec3::X, 4.999).hit);
    assert!(both(&bits, Vec3::new(0.0, 5.5, 5.5), Vec3::X, 5.0).hit);
}

#[test]
fn tiny_and_zero_direction_components() {
    let mut rng = Rng(99);
    let bits = random_grid(&mut rng, 12, 12, 1, 0.02);
    for _ in 0..300 {
        let o = Vec3::new(
            rng.range(0.0, 12.0),
            rng.range(0.0, 12.0),
            rng.range(0.0, 128.0),
        );
        let mut d = rng.unit();
        let axis = rng.below(3) as usize;
        d[axis] = 0.0;
        let exact = both(&bits, o, d, f32::INFINITY);
        for tiny in [1e-30, -1e-30, 1e-38, -f32::MIN_POSITIVE] {
            let mut dt = d;
            dt[axis] = tiny;
            let r = both(&bits, o, dt, f32::INFINITY);
            assert_eq!((r.hit, r.voxel, r.t), (exact.hit, exact.voxel, exact.t));
        }
        // A direction scaled by 1e-30 describes the same ray with t scaled by 1e30.
        let r = both(&bits, o, d * 1e-30, f32::INFINITY);
        assert_eq!((r.hit, r.voxel), (exact.hit, exact.voxel));
        if r.hit {
            assert!((r.t * 1e-30 - exact.t).abs() <= 1e-5 * exact.t.max(1.0));
        }
    }
    // Grazing: almost parallel to a wall of voxels at k = 40, hits it far away.
    let mut wall = BitGrid::new(64, 4, 1);
    for x in 0..64 {
        for y in 0..4 {
            wall.set(x, y, 40);
        }
    }
    let r = both(
        &wall,
        Vec3::new(0.0, 1.5, 39.99),
        Vec3::new(1.0, 0.0, 1e-3),
        f32::INFINITY,
    );
    // 39.99 rounds in f32, so the wall is reached at x ≈ 10 from either side.
    assert!(
        r.hit && r.voxel.z == 40 && (9..=10).contains(&r.voxel.x),
        "{r:?}"
    );
}

#[test]
fn misses_degenerate_and_invalid_rays() {
    let mut bits = BitGrid::new(4, 4, 1);
    bits.set(1, 1, 1);
    let h = BitHierarchy::build(bits.clone());
    let p = GENEROUS;
    // Starting outside and missing: resolved at once.
    let r = first_hit_hierarchical(
        &h,
        Vec3::new(-5.0, -5.0, -5.0),
        -Vec3::ONE,
        f32::INFINITY,
        &p,
    );
    assert!(!r.hit && !r.ran_out && r.steps == 0);
    let r = both(&bits, Vec3::new(-5.0, 1.5, 1.5), Vec3::Y, f32::INFINITY);
    assert!(!r.hit);
    // Starting far outside and coming in.
    let r = both(&bits, Vec3::new(-1e30, 1.5, 1.5), Vec3::X, f32::INFINITY);
    assert!(r.hit && r.voxel == UVec3::new(1, 1, 1));
    // Zero direction and zero-length segments query the start voxel only.
    assert!(both(&bits, Vec3::splat(1.5), Vec3::ZERO, 1.0).hit);
    assert!(!both(&bits, Vec3::splat(2.5), Vec3::ZERO, 1.0).hit);
    assert!(both(&bits, Vec3::splat(1.5), Vec3::X, 0.0).hit);
    assert!(!visible(&h, Vec3::splat(1.5), Vec3::splat(1.5), &p));
    assert!(visible(&h, Vec3::splat(2.5), Vec3::splat(2.5), &p));
    // Reversed segment through the voxel.
    let (a, b) = (Vec3::new(0.5, 1.5, 1.5), Vec3::new(3.5, 1.5, 1.5));
    assert!(!visible(&h, a, b, &p) && !visible(&h, b, a, &p));
    // Negative t_max, NaN and Inf: a miss, never a panic.
    for (o, d, t) in [
        (Vec3::splat(1.5), Vec3::X, -1.0),
        (Vec3::splat(f32::NAN), Vec3::X, 1.0),
        (Vec3::splat(1.5), Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
        (Vec3::splat(1.5), Vec3::new(f32::INFINITY, 1.0, 0.0), 1.0),
        (Vec3::splat(1.5), Vec3::X, f32::NAN),
    ] {
        let r = both(&bits, o, d, t);
        assert!(!r.hit && !r.position.is_nan());
        assert!(!march_1bit(&bits, o, d, t, 8).hit);
        assert!(!march_3bit(&bits, o, d, t, 8).hit);
    }
}

#[test]
fn iteration_cap_reports_ran_out() {
    let mut bits = BitGrid::new(64, 64, 1);
    bits.set(63, 63, 127);
    let h = BitHierarchy::build(bits.clone());
    let o = Vec3::new(0.5, 0.3, 0.2);
    let d = Vec3::new(63.0, 63.2, 127.3) - o;
    let capped = TraversalParams {
        start_level: 0,
        max_iterations: 3,
    };
    let r = first_hit_hierarchical(&h, o, d, 1.0, &capped);
    assert!(!r.hit && r.ran_out && r.steps == 3);
    assert!(
        visible(&h, o, o + d, &capped),
        "a capped ray counts as visible (Thiedemann 2010, §5.3.2)"
    );
    let r = first_hit_hierarchical(&h, o, d, 1.0, &GENEROUS);
    assert!(r.hit && r.voxel == UVec3::new(63, 63, 127));
    // Empty-space skipping: far fewer iterations than voxels visited by the DDA.
    let dda = first_hit_dda(&bits, o, d, 1.0);
    assert!(r.steps < dda.steps, "{} vs {}", r.steps, dda.steps);
}

#[test]
fn scaled_worlds_give_the_same_hits() {
    let mut rng = Rng(5);
    let base = random_grid(&mut rng, 20, 12, 1, 0.01);
    let rays: Vec<(Vec3, Vec3)> = (0..2000)
        .map(|_| {
            let o = Vec3::new(
                rng.range(-1.0, 6.0),
                rng.range(-1.0, 4.0),
                rng.range(-0.5, 2.5),
            );
            (o, rng.unit())
        })
        .collect();
    let h = BitHierarchy::build(base.clone());
    let mut results: Vec<Vec<(bool, UVec3)>> = Vec::new();
    for scale in [1e-3f32, 1.0, 1e4] {
        // World box [−1.7, 5.3] × [0.5, 3.5] × [0, 1.28] m, scaled; looks along z.
        let g = VoxelGrid::from_box(
            Vec3::new(-1.7, 0.5, 0.0) * scale,
            Vec3::new(5.3, 3.5, 1.28) * scale,
            Some(Axis::Z),
            20,
            12,
            1,
        )
        .unwrap();
        results.push(
            rays.iter()
                .map(|&(o, d)| {
                    let ov = g.world_to_voxel(o * scale);
                    let dv = g.dir_world_to_voxel(d * scale);
                    let r = first_hit_hierarchical(&h, ov, dv, f32::INFINITY, &GENEROUS);
                    assert!(!r.ran_out && !r.t.is_nan());
                    (r.hit, r.voxel)
                })
                .collect(),
        );
    }
    let hits = results[1].iter().filter(|r| r.0).count();
    assert!(hits > 200, "test should exercise hits, got {hits}");
    for other in [&results[0], &results[2]] {
        let differ = other
            .iter()
            .zip(&results[1])
            .filter(|(a, b)| a != b)
            .count();
        // Rounding differs between scales; only rays passing within f32 noise of a voxel
        // boundary may change voxel, and random rays almost never do.
        assert!(differ <= 2, "{differ} of {} rays changed", rays.len());
    }
}

#[test]
fn marching_baselines() {
    // A one-voxel-thick wall across the whole grid at depth 50.
    let mut wall = BitGrid::new(4, 4, 1);
    for x in 0..4 {
        for y in 0..4 {
            wall.set(x, y, 50);
        }
    }
    let o = Vec3::new(1.5, 1.5, 0.0);
    // 128 / 40 = 3.2 voxels per sample: samples at k = 1.6, 4.8, …, 48.0, 51.2 skip 50.
    let one = march_1bit(&wall, o, Vec3::Z, f32::INFINITY, 40);
    let three = march_3bit(&wall, o, Vec3::Z, f32::INFINITY, 40);
    assert!(
        !one.hit,
        "the 1-bit march misses a thin wall between samples"
    );
    assert!(
        three.hit && three.voxel == UVec3::new(1, 1, 50),
        "{three:?}"
    );
    // Dense sampling converges to the exact answer.
    let dense = march_1bit(&wall, o, Vec3::Z, f32::INFINITY, 1024);
    assert!(dense.hit && dense.voxel == UVec3::new(1, 1, 50));
    // False hit of the thick mask: a ray parallel to the wall one voxel in front of it.
    let par = Vec3::new(0.0, 1.5, 49.5);
    assert!(!first_hit_dda(&wall, par, Vec3::X, f32::INFINITY).hit);
    assert!(march_3bit(&wall, par, Vec3::X, f32::INFINITY, 16).hit);
    assert!(!march_1bit(&wall, par, Vec3::X, f32::INFINITY, 16).hit);
    // Backwards along −z the 3-bit mask reports the neighbour nearest along the ray.
    let back = march_3bit(
        &wall,
        Vec3::new(1.5, 1.5, 128.0),
        -Vec3::Z,
        f32::INFINITY,
        40,
    );
    assert!(back.hit && back.voxel.z == 50);
    // On random grids a dense 1-bit march never reports a voxel the ray does not visit
    // before the DDA's... it may only miss or hit later.
    let mut rng = Rng(31);
    let bits = random_grid(&mut rng, 8, 8, 2, 0.01);
    for _ in 0..500 {
        let (o, d, t_max) = random_ray(&mut rng, UVec3::new(8, 8, 256));
        let exact = first_hit_dda(&bits, o, d, t_max);
        let m = march_1bit(&bits, o, d, t_max, 64);
        if m.hit {
            assert!(
                exact.hit && m.t >= exact.t - 1e-3 * exact.t.abs().max(1.0),
                "{m:?} {exact:?}"
            );
        }
    }
}

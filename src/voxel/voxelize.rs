//! Exact CPU surface voxelizer: the reference for the GPU voxelization passes.
//!
//! Every voxel whose *closed* box `[i,i+1]×[j,j+1]×[k,k+1]` (voxel space) the triangle
//! overlaps is set, decided by the Akenine-Möller triangle/box separating-axis test
//! (Akenine-Möller 2001, "Fast 3D triangle-box overlap testing": the triangle's plane cuts the box
//! and the 2D projections overlap, plus the nine edge×axis axes). Touching counts, so a triangle
//! lying exactly on a voxel face sets the voxels on both sides: the reference is conservative,
//! never thinner than a GPU voxelizer that rounds depths either way.
//!
//! The test runs in voxel space: the world→voxel map is affine, and affine maps preserve
//! overlap, so the unit voxel boxes are exact there.
//!
//! Degenerate triangles need no special path: for a zero normal the plane test is skipped and
//! the remaining axes are exactly the separating axes of a segment (box normals and
//! segment×box axes) or of a point (box normals). Near-degenerate slivers whose normal f32
//! cannot resolve are treated the same way, which can only add voxels along the sliver.

use glam::{UVec3, Vec3};

use super::coverage::{object_coverage, Coverage};
use super::{BitGrid, VoxelError, VoxelGrid};

/// Counters of one voxelization call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VoxelizeStats {
    /// Triangles processed.
    pub triangles: u64,
    /// Triangles with (numerically) zero area, voxelized as a segment or point.
    pub degenerate: u64,
    /// Triangles entirely outside the grid.
    pub outside: u64,
    /// Voxel boxes tested.
    pub box_tests: u64,
}

/// `|n|² ≤ DEGENERATE_REL · |e0|²·|e1|²`, i.e. the sine of the angle between the edges is
/// below ~3e-5: f32 cross products of nearly parallel edges are noise at that level.
pub(crate) const DEGENERATE_REL: f32 = 1e-9;

fn is_degenerate(e0: Vec3, e1: Vec3, n: Vec3) -> bool {
    n.length_squared() <= DEGENERATE_REL * e0.length_squared() * e1.length_squared()
}

/// Akenine-Möller triangle/box overlap test (closed box `center ± half`).
pub fn tri_box_overlap(center: Vec3, half: Vec3, tri: [Vec3; 3]) -> bool {
    let v = [tri[0] - center, tri[1] - center, tri[2] - center];
    // 1. Box face normals: AABB of the triangle against the box.
    let lo = v[0].min(v[1]).min(v[2]);
    let hi = v[0].max(v[1]).max(v[2]);
    if lo.cmpgt(half).any() || hi.cmplt(-half).any() {
        return false;
    }
    // 2. The nine cross products of box axes and triangle edges. A zero axis (degenerate
    //    edge) projects everything to 0 and separates nothing, as it should.
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    for e in edges {
        for axis in [Vec3::X.cross(e), Vec3::Y.cross(e), Vec3::Z.cross(e)] {
            let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
            let rad = half.dot(axis.abs());
            let (pmin, pmax) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            if pmin > rad || pmax < -rad {
                return false;
            }
        }
    }
    // 3. The triangle's plane against the box: test the two box corners extremal along n.
    let n = edges[0].cross(edges[1]);
    if is_degenerate(edges[0], edges[1], n) {
        return true;
    }
    let d = n.dot(v[0]);
    let r = half.dot(n.abs());
    (d - r) <= 0.0 && (d + r) >= 0.0
}

/// Voxelizes one triangle given in voxel-space coordinates; the part outside the grid is
/// clipped. Vertices must be finite (checked by the public entry points).
fn voxelize_voxel_space(
    bits: &mut BitGrid,
    tri: [Vec3; 3],
    coverage: Coverage,
    stats: &mut VoxelizeStats,
) {
    stats.triangles += 1;
    let dims = UVec3::new(bits.res_x(), bits.res_y(), bits.depth());
    let dims_f = dims.as_vec3();
    let lo = tri[0].min(tri[1]).min(tri[2]);
    let hi = tri[0].max(tri[1]).max(tri[2]);
    // Closed boxes: a vertex at exactly x = 3 touches voxels 2 and 3.
    if hi.cmplt(Vec3::ZERO).any() || lo.cmpgt(dims_f).any() {
        stats.outside += 1;
        return;
    }
    let e0 = tri[1] - tri[0];
    let e1 = tri[2] - tri[1];
    let n = e0.cross(e1);
    let degenerate = is_degenerate(e0, e1, n);
    if degenerate {
        stats.degenerate += 1;
    }
    // Clamp in float before converting so huge coordinates cannot overflow the integer cast.
    let first = (lo.ceil() - 1.0).clamp(Vec3::ZERO, dims_f - 1.0).as_uvec3();
    let last = hi.floor().clamp(Vec3::ZERO, dims_f - 1.0).as_uvec3();
    // Per column, the plane bounds the depth range (a pure speed-up: the SAT test decides).
    // Only used where the plane is not steep, so the bound is tight and well conditioned.
    let use_plane = !degenerate && n.z.abs() >= 0.1 * n.length();
    let half = Vec3::splat(0.5);
    for y in first.y..=last.y {
        for x in first.x..=last.x {
            let (mut k0, mut k1) = (first.z, last.z);
            if use_plane {
                // z on the plane over the column square, widened by a voxel for rounding.
                let z_at = |px: f32, py: f32| {
                    tri[0].z - (n.x * (px - tri[0].x) + n.y * (py - tri[0].y)) / n.z
                };
                let (x0, x1, y0, y1) = (x as f32, x as f32 + 1.0, y as f32, y as f32 + 1.0);
                let zs = [z_at(x0, y0), z_at(x1, y0), z_at(x0, y1), z_at(x1, y1)];
                let zmin = zs[0].min(zs[1]).min(zs[2]).min(zs[3]) - 1.0;
                let zmax = zs[0].max(zs[1]).max(zs[2]).max(zs[3]) + 1.0;
                k0 = k0.max(zmin.floor().clamp(0.0, dims_f.z - 1.0) as u32);
                k1 = k1.min(zmax.floor().clamp(0.0, dims_f.z - 1.0) as u32);
            }
            for k in k0..=k1 {
                stats.box_tests += 1;
                let c = Vec3::new(x as f32, y as f32, k as f32) + half;
                if tri_box_overlap(c, half, tri) && coverage.covers(UVec3::new(x, y, k)) {
                    bits.set(x, y, k);
                }
            }
        }
    }
}

fn check_dims(grid: &VoxelGrid, bits: &BitGrid) -> Result<(), VoxelError> {
    let expected = (grid.res_x(), grid.res_y(), grid.layers());
    if bits.dims() != expected {
        return Err(VoxelError::GridMismatch {
            got: bits.dims(),
            expected,
        });
    }
    Ok(())
}

/// Voxelizes world-space triangles into `bits`. All vertices are checked before any bit is
/// written, so on error `bits` is unchanged.
pub fn voxelize_triangles(
    grid: &VoxelGrid,
    bits: &mut BitGrid,
    triangles: &[[Vec3; 3]],
) -> Result<VoxelizeStats, VoxelError> {
    check_dims(grid, bits)?;
    for (i, tri) in triangles.iter().enumerate() {
        if let Some(&vertex) = tri.iter().find(|v| !v.is_finite()) {
            return Err(VoxelError::NonFiniteVertex {
                triangle: i,
                vertex,
            });
        }
    }
    let mut stats = VoxelizeStats::default();
    for tri in triangles {
        let t = tri.map(|p| grid.world_to_voxel(p));
        voxelize_voxel_space(bits, t, Coverage::OPAQUE, &mut stats);
    }
    Ok(stats)
}

/// Voxelizes an indexed world-space triangle list. Validates indices and vertices first, so on
/// error `bits` is unchanged.
pub fn voxelize_mesh(
    grid: &VoxelGrid,
    bits: &mut BitGrid,
    positions: &[Vec3],
    indices: &[u32],
) -> Result<VoxelizeStats, VoxelError> {
    voxelize_mesh_covered(grid, bits, positions, indices, &[])
}

/// [`voxelize_mesh`] with each triangle's [`Coverage`] (`coverage[t]` for triangle t; those
/// past its end are opaque).
pub fn voxelize_mesh_covered(
    grid: &VoxelGrid,
    bits: &mut BitGrid,
    positions: &[Vec3],
    indices: &[u32],
    coverage: &[Coverage],
) -> Result<VoxelizeStats, VoxelError> {
    check_dims(grid, bits)?;
    if !indices.len().is_multiple_of(3) {
        return Err(VoxelError::BadIndexCount { len: indices.len() });
    }
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        for &index in tri {
            let vertex = *positions
                .get(index as usize)
                .ok_or(VoxelError::IndexOutOfRange {
                    triangle: t,
                    index,
                    count: positions.len(),
                })?;
            if !vertex.is_finite() {
                return Err(VoxelError::NonFiniteVertex {
                    triangle: t,
                    vertex,
                });
            }
        }
    }
    let mut stats = VoxelizeStats::default();
    for (i, tri) in indices.chunks_exact(3).enumerate() {
        let t = [tri[0], tri[1], tri[2]].map(|i| grid.world_to_voxel(positions[i as usize]));
        let c = coverage.get(i).copied().unwrap_or(Coverage::OPAQUE);
        voxelize_voxel_space(bits, t, c, &mut stats);
    }
    Ok(stats)
}

/// Voxelizes every object of `scene` at time `t_s` (its world-space triangles, with their
/// materials' opacity as [`Coverage`]) into `bits`.
pub fn voxelize_scene(
    grid: &VoxelGrid,
    bits: &mut BitGrid,
    scene: &crate::scene::Scene,
    t_s: f32,
) -> Result<VoxelizeStats, VoxelError> {
    let mut total = VoxelizeStats::default();
    for object in &scene.objects {
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let m = object.transform_at(t_s);
        let world: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| m.transform_point3(*p))
            .collect();
        let coverage = object_coverage(scene, object, object.mesh_at(t_s));
        let s = voxelize_mesh_covered(grid, bits, &world, &mesh.indices, &coverage)?;
        total.triangles += s.triangles;
        total.degenerate += s.degenerate;
        total.outside += s.outside;
        total.box_tests += s.box_tests;
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Unit voxel-space grid: world = voxel coordinates.
    fn unit_grid(w: u32, h: u32, layers: u32) -> VoxelGrid {
        let d = (128 * layers) as f32;
        VoxelGrid::from_box(
            Vec3::ZERO,
            Vec3::new(w as f32, h as f32, d),
            Some(crate::voxel::Axis::Z),
            w,
            h,
            layers,
        )
        .unwrap()
    }

    /// Independent SAT in f64 over all 13 axes, projecting the 8 box corners explicitly.
    fn sat_f64(lo: DVec3, hi: DVec3, tri: [DVec3; 3]) -> bool {
        let e = [tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]];
        let mut axes = vec![DVec3::X, DVec3::Y, DVec3::Z, e[0].cross(e[1])];
        for ei in e {
            for a in [DVec3::X, DVec3::Y, DVec3::Z] {
                axes.push(a.cross(ei));
            }
        }
        for axis in axes {
            if axis.length_squared() < 1e-24 {
                continue;
            }
            let pt: Vec<f64> = tri.iter().map(|v| v.dot(axis)).collect();
            let mut pb = Vec::new();
            for i in 0..8 {
                let c = DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                pb.push(c.dot(axis));
            }
            let (tmin, tmax) = pt
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            let (bmin, bmax) = pb
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            if tmin > bmax || tmax < bmin {
                return false;
            }
        }
        true
    }

    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
    }

    #[test]
    fn axis_aligned_quad_sets_exact_slab() {
        let g = unit_grid(16, 16, 1);
        let mut bits = BitGrid::for_grid(&g);
        let (a, b, c, d) = (
            Vec3::new(2.5, 3.5, 5.5),
            Vec3::new(6.5, 3.5, 5.5),
            Vec3::new(6.5, 9.5, 5.5),
            Vec3::new(2.5, 9.5, 5.5),
        );
        voxelize_triangles(&g, &mut bits, &[[a, b, c], [a, c, d]]).unwrap();
        for y in 0..16 {
            for x in 0..16 {
                for k in 0..128 {
                    let want = (2..=6).contains(&x) && (3..=9).contains(&y) && k == 5;
                    assert_eq!(bits.get(x, y, k), want, "({x},{y},{k})");
                }
            }
        }
        // On a voxel face the closed-box rule sets both neighbours.
        let mut bits = BitGrid::for_grid(&g);
        let z = Vec3::new(0.0, 0.0, 0.5);
        voxelize_triangles(&g, &mut bits, &[[a - z, b - z, c - z]]).unwrap();
        assert!(bits.get(4, 4, 4) && bits.get(4, 4, 5) && !bits.get(4, 4, 6));
    }

    #[test]
    fn matches_brute_force_sat() {
        let mut rng = Lcg(7);
        for layers in [1, 2] {
            let g = unit_grid(9, 7, layers);
            let dims = g.extent_voxels().as_vec3();
            for _ in 0..40 {
                let mut bits = BitGrid::for_grid(&g);
                // Vertices spill outside the grid to exercise clipping; keep z near the grid.
                let tri = [0; 3].map(|_| {
                    Vec3::new(
                        rng.next() * 13.0 - 2.0,
                        rng.next() * 11.0 - 2.0,
                        rng.next() * 14.0 - 2.0,
                    ) + Vec3::new(0.0, 0.0, (dims.z - 10.0) * rng.next())
                });
                voxelize_triangles(&g, &mut bits, &[tri]).unwrap();
                let t64 = tri.map(|v| v.as_dvec3());
                for k in 0..g.depth() {
                    for y in 0..7 {
                        for x in 0..9 {
                            let lo = DVec3::new(x as f64, y as f64, k as f64);
                            let grown = sat_f64(lo - 1e-4, lo + 1.0 + 1e-4, t64);
                            let shrunk = sat_f64(lo + 1e-4, lo + 1.0 - 1e-4, t64);
                            let got = bits.get(x, y, k);
                            assert!(!shrunk || got, "missed voxel ({x},{y},{k}) of {tri:?}");
                            assert!(!got || grown, "extra voxel ({x},{y},{k}) of {tri:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn degenerate_triangles() {
        let g = unit_grid(8, 8, 1);
        // A point sets the voxel containing it.
        let mut bits = BitGrid::for_grid(&g);
        let p = Vec3::new(3.5, 2.5, 7.5);
        let s = voxelize_triangles(&g, &mut bits, &[[p, p, p]]).unwrap();
        assert_eq!(s.degenerate, 1);
        assert_eq!(bits.count_ones(), 1);
        assert!(bits.get(3, 2, 7));
        // A collinear triangle sets exactly the voxels its segment passes through.
        let mut bits = BitGrid::for_grid(&g);
        let (a, b) = (Vec3::new(0.5, 0.5, 0.5), Vec3::new(5.5, 0.5, 0.5));
        voxelize_triangles(&g, &mut bits, &[[a, b, 0.5 * (a + b)]]).unwrap();
        assert_eq!(bits.count_ones(), 6);
        assert!((0..6).all(|x| bits.get(x, 0, 0)));
        // A diagonal segment: every voxel whose box it touches, no others.
        let mut bits = BitGrid::for_grid(&g);
        let (a, b) = (Vec3::new(0.3, 0.6, 1.2), Vec3::new(6.7, 4.1, 9.9));
        voxelize_triangles(&g, &mut bits, &[[a, b, b]]).unwrap();
        let t64 = [a, b, b].map(|v| v.as_dvec3());
        for k in 0..16 {
            for y in 0..8 {
                for x in 0..8 {
                    let lo = DVec3::new(x as f64, y as f64, k as f64);
                    let shrunk = sat_f64(lo + 1e-4, lo + 1.0 - 1e-4, t64);
                    let grown = sat_f64(lo - 1e-4, lo + 1.0 + 1e-4, t64);
                    let got = bits.get(x, y, k);
                    assert!((!shrunk || got) && (!got || grown), "({x},{y},{k})");
                }
            }
        }
        assert!(bits.count_ones() >= 9);
        // Sliver: three nearly collinear points, no NaN, no panic, contains the vertices.
        let mut bits = BitGrid::for_grid(&g);
        let tri = [a, b, 0.5 * (a + b) + Vec3::new(0.0, 1e-7, 0.0)];
        voxelize_triangles(&g, &mut bits, &[tri]).unwrap();
        assert!(bits.get(0, 0, 1) && bits.get(6, 4, 9));
    }

    #[test]
    fn clipping_and_outside() {
        let g = unit_grid(4, 4, 1);
        let mut bits = BitGrid::for_grid(&g);
        let far = Vec3::splat(1e30);
        let s = voxelize_triangles(&g, &mut bits, &[[far, far * 2.0, far * 3.0]]).unwrap();
        assert_eq!((s.outside, bits.count_ones()), (1, 0));
        // Huge triangle through the grid: a full z = 10.5 slab, nothing else.
        let big = [
            Vec3::new(-1e6, -1e6, 10.5),
            Vec3::new(1e6, -1e6, 10.5),
            Vec3::new(0.0, 1e6, 10.5),
        ];
        voxelize_triangles(&g, &mut bits, &[big]).unwrap();
        assert_eq!(bits.count_ones(), 16);
        assert!((0..4).all(|x| (0..4).all(|y| bits.get(x, y, 10))));
    }

    #[test]
    fn rejects_bad_input_without_writing() {
        let g = unit_grid(4, 4, 1);
        let mut bits = BitGrid::for_grid(&g);
        let ok = [
            Vec3::ONE,
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(1.0, 2.0, 1.0),
        ];
        let nan = [Vec3::ONE, Vec3::new(f32::NAN, 1.0, 1.0), Vec3::ONE];
        let err = voxelize_triangles(&g, &mut bits, &[ok, nan]).unwrap_err();
        assert!(matches!(
            err,
            VoxelError::NonFiniteVertex { triangle: 1, .. }
        ));
        assert_eq!(bits.count_ones(), 0);
        let pos = [Vec3::ONE, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::ZERO];
        assert!(matches!(
            voxelize_mesh(&g, &mut bits, &pos, &[0, 2, 1]),
            Err(VoxelError::NonFiniteVertex { triangle: 0, .. })
        ));
        assert!(matches!(
            voxelize_mesh(&g, &mut bits, &pos, &[0, 2, 3]),
            Err(VoxelError::IndexOutOfRange { index: 3, .. })
        ));
        assert!(matches!(
            voxelize_mesh(&g, &mut bits, &pos, &[0, 2]),
            Err(VoxelError::BadIndexCount { len: 2 })
        ));
        let mut wrong = BitGrid::new(4, 4, 2);
        assert!(matches!(
            voxelize_triangles(&g, &mut wrong, &[ok]),
            Err(VoxelError::GridMismatch { .. })
        ));
        let pos = [
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(3.5, 0.5, 0.5),
            Vec3::new(0.5, 3.5, 0.5),
        ];
        voxelize_mesh(&g, &mut bits, &pos, &[0, 1, 2]).unwrap();
        // Closed boxes under the hypotenuse x + y = 4: voxels with x + y ≤ 4 (corners touch).
        assert_eq!(bits.count_ones(), 13);
        assert!(bits.get(1, 3, 0) && !bits.get(2, 3, 0));
    }

    #[test]
    fn world_space_mesh_any_axis() {
        // The same quad in a grid looking along X lands in depth = world x.
        let g = VoxelGrid::from_box(
            Vec3::ZERO,
            Vec3::new(1.28, 0.8, 0.8),
            Some(crate::voxel::Axis::X),
            8,
            8,
            1,
        )
        .unwrap();
        let mut bits = BitGrid::for_grid(&g);
        let x = 0.505; // depth voxel 50 (voxel 0.01 m)
        let pos = [
            Vec3::new(x, 0.05, 0.05),
            Vec3::new(x, 0.75, 0.05),
            Vec3::new(x, 0.75, 0.75),
            Vec3::new(x, 0.05, 0.75),
        ];
        voxelize_mesh(&g, &mut bits, &pos, &[0, 1, 2, 0, 2, 3]).unwrap();
        assert_eq!(bits.count_ones(), 64);
        assert!(bits.get(3, 5, 50));
    }
}

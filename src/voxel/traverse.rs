//! CPU twin of the GPU ray test (Thiedemann 2010, §5.3; the uniform marching baselines of §6.4.1), written to port line by line to GLSL:
//! plain loops, no recursion, f32 math, integer bit operations on `uvec4` columns.
//!
//! All functions work in **voxel space** (see [`super`]): `origin + t·dir`, `t ∈ [0, t_max]`.
//! Map a world ray with [`VoxelGrid::world_to_voxel`](super::VoxelGrid::world_to_voxel) and
//! [`VoxelGrid::dir_world_to_voxel`](super::VoxelGrid::dir_world_to_voxel); `t` is then the
//! same in both spaces.
//!
//! # Which voxels a ray visits
//! Voxels are half-open boxes, and a ray visits `{ floor(p(t)) : t ∈ [t0, t1] }` where
//! `[t0, t1]` is the ray clipped to the grid and to `[0, t_max]`. Every decision "has the ray
//! crossed boundary b at parameter t" is made by one comparison, `t ≥ (b − o)/d` computed as
//! [`boundary_t`], in the hierarchical traversal and in the DDA alike; a boundary crossed by
//! two axes at the same parameter steps both (the ray passes exactly through an edge or
//! corner). The hierarchical test therefore returns bit-for-bit the DDA's voxel and `t`.
//!
//! # Deviations from the thesis, and why
//! - The thesis advances past an empty box by `t = t_exit + ε` and re-derives the column
//!   from the position (§5.3.2). An ε gap can skip a voxel corner the ray clips, and a too-small
//!   ε sticks on the boundary at large coordinates. Here the next column is found by integer
//!   stepping across the exit face (as in Amanatides–Woo), so no gap exists and progress is
//!   guaranteed; there is no ε parameter.
//! - The depth range of a segment inside a column is derived from the same boundary
//!   comparisons rather than by quantizing `z` (§5.3.2), so the ray mask is exact.
//! - The voxel-accurate hit (§5.3.4) solves `t` at the entry of the hit voxel along the ray
//!   instead of replacing only the position's z.
//! - The ray is first rebased to its entry point into the grid, so rays starting far outside
//!   keep full precision inside.
//!
//! # Guard for tiny direction components
//! The direction is scaled so its largest component is ±1; components below
//! [`DIR_EPS`] are then treated as exactly 0 (the ray drifts less than `DIR_EPS · 3·16384`
//! voxels over the largest grid). This replaces the thesis's "replace tiny components by a
//! tiny value" (§5.3.2) and keeps every `1/d` finite.

use glam::{IVec3, UVec3, Vec3};

use super::bits::{col_and, col_highest_bit, col_is_empty, col_lowest_bit, BitGrid, BitHierarchy};
use super::ray_mask::column_mask;
use super::COLUMN_BITS;

/// Direction components below this (after scaling the largest to 1) count as 0.
pub const DIR_EPS: f32 = 1e-12;

/// Parameters of the hierarchical traversal (thesis §5.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraversalParams {
    /// Mip level to start at (clamped to the coarsest). The thesis's example starts at 1.
    pub start_level: u32,
    /// Iteration cap; exceeding it ends the ray with no hit and `ran_out = true`. Too low a
    /// cap shows as missing shadows (thesis Fig. 46).
    pub max_iterations: u32,
}

impl Default for TraversalParams {
    fn default() -> Self {
        Self {
            start_level: 1,
            max_iterations: 1024,
        }
    }
}

/// Result of a ray query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitResult {
    pub hit: bool,
    /// Hit voxel `(x, y, k)`; zero when there is no hit.
    pub voxel: UVec3,
    /// Ray parameter where the ray enters the hit voxel (or the marching sample that hit), in
    /// the caller's parameterization; `f32::INFINITY` when there is no hit.
    pub t: f32,
    /// Voxel-space point at `t` (NaN-free; the origin when there is no hit).
    pub position: Vec3,
    /// Loop iterations (hierarchical), voxels visited (DDA) or samples taken (marching).
    pub steps: u32,
    /// The iteration cap ended the ray before it was resolved.
    pub ran_out: bool,
}

impl HitResult {
    fn miss(origin: Vec3, steps: u32, ran_out: bool) -> Self {
        Self {
            hit: false,
            voxel: UVec3::ZERO,
            t: f32::INFINITY,
            position: if origin.is_finite() {
                origin
            } else {
                Vec3::ZERO
            },
            steps,
            ran_out,
        }
    }
}

/// Ray parameter at which a ray from `o` with direction component `d` crosses coordinate `b`
/// (`inv = 1/d`). The one formula behind every boundary decision.
#[inline]
pub fn boundary_t(b: f32, o: f32, inv: f32) -> f32 {
    (b - o) * inv
}

/// A ray prepared for traversal: scaled, guarded, clipped to the grid and rebased.
#[derive(Clone, Copy, Debug)]
struct Ray {
    /// Entry point into the grid (`origin + t0·dir`).
    o: Vec3,
    /// Direction with largest component ±1; tiny components are exactly 0.
    d: Vec3,
    /// `1/d` per axis; 0 on axes where `d` is 0 (never used there).
    inv: Vec3,
    /// Segment end, in the rebased scaled parameter.
    t_end: f32,
    /// Scaled parameter of the entry point along the caller's ray.
    t_base: f32,
    /// Largest absolute component of the caller's direction; `t_caller = t_scaled / scale`.
    scale: f32,
    dims: IVec3,
}

enum Setup {
    /// Invalid input, or the ray misses the grid.
    Miss,
    /// Zero direction, or a clipped ray of zero length: only this voxel is visited, at this
    /// caller parameter and voxel-space point.
    Point(IVec3, f32, Vec3),
    Ray(Ray),
}

fn setup_ray(dims: UVec3, origin: Vec3, dir: Vec3, t_max: f32) -> Setup {
    // NaN anywhere, or an infinite origin/direction: nothing sensible to trace.
    if !(origin.is_finite() && dir.is_finite()) || t_max.is_nan() || t_max < 0.0 {
        return Setup::Miss;
    }
    let dims_f = dims.as_vec3();
    let scale = dir.abs().max_element();
    if scale == 0.0 {
        if origin.cmpge(Vec3::ZERO).all() && origin.cmplt(dims_f).all() {
            return Setup::Point(origin.floor().as_ivec3(), 0.0, origin);
        }
        return Setup::Miss;
    }
    let mut d = dir / scale;
    let mut inv = Vec3::ZERO;
    let mut t0 = 0.0f32;
    // `t_max · scale` may overflow to +inf; that is a valid "unbounded" end.
    let t_lim = t_max * scale;
    let mut t1 = t_lim;
    for i in 0..3 {
        if d[i].abs() < DIR_EPS {
            d[i] = 0.0;
            // Parallel to this slab: inside (half-open) or a miss.
            if !(origin[i] >= 0.0 && origin[i] < dims_f[i]) {
                return Setup::Miss;
            }
        } else {
            inv[i] = 1.0 / d[i];
            let ta = boundary_t(0.0, origin[i], inv[i]);
            let tb = boundary_t(dims_f[i], origin[i], inv[i]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    // No NaN can reach here: origin and 1/d are finite, t_max is not NaN.
    if t0 > t1 {
        return Setup::Miss;
    }
    // Rebase to the entry point and clip again from there: `t1 − t0` would lose all precision
    // for a ray starting far outside (t0 = 1e30, t1 = 1e30 + 4).
    let o = origin + t0 * d;
    let mut t_end = t_lim - t0;
    for i in 0..3 {
        if d[i] != 0.0 {
            let ta = boundary_t(0.0, o[i], inv[i]);
            let tb = boundary_t(dims_f[i], o[i], inv[i]);
            t_end = t_end.min(ta.max(tb));
        }
    }
    let ray = Ray {
        o,
        d,
        inv,
        t_end: t_end.max(0.0),
        t_base: t0,
        scale,
        dims: dims.as_ivec3(),
    };
    if ray.t_end > 0.0 {
        return Setup::Ray(ray);
    }
    // The clipped ray is a single point (t_max = 0, or the ray only touches the grid's
    // boundary): it visits the cell it is entering there, which may be outside.
    let c = IVec3::new(
        ray.cell_at(0, 0.0, false),
        ray.cell_at(1, 0.0, false),
        ray.cell_at(2, 0.0, false),
    );
    if c.cmplt(IVec3::ZERO).any() || c.cmpge(ray.dims).any() {
        return Setup::Miss;
    }
    Setup::Point(c, ray.t_base / scale, o)
}

impl Ray {
    /// Parameter at which the ray enters cell `c` along axis `i` (`d[i] ≠ 0`).
    #[inline]
    fn enter_t(&self, i: usize, c: i32) -> f32 {
        let b = if self.d[i] > 0.0 {
            c as f32
        } else {
            c as f32 + 1.0
        };
        boundary_t(b, self.o[i], self.inv[i])
    }

    /// Cell index along axis `i` at parameter `t`: the cell entered at or before `t`
    /// (`strict = false`), or strictly before `t` (`strict = true`, the cell the ray occupied
    /// just before reaching `t`). The float estimate `floor(o + t·d)` is at most one cell off
    /// (the ray is rebased, so `|o|, |t·d|` are grid-sized) and is corrected by comparing
    /// boundary parameters, so the answer agrees with every other boundary decision.
    #[inline]
    fn cell_at(&self, i: usize, t: f32, strict: bool) -> i32 {
        let d = self.d[i];
        if d == 0.0 {
            return self.o[i].floor() as i32;
        }
        let step = if d > 0.0 { 1 } else { -1 };
        let mut c = (self.o[i] + t * d).floor() as i32;
        let e = self.enter_t(i, c);
        if e > t || (strict && e == t) {
            c -= step;
        } else {
            let e_next = self.enter_t(i, c + step);
            if e_next < t || (!strict && e_next == t) {
                c += step;
            }
        }
        c
    }

    /// [`Self::cell_at`] at `t` both ways, `(non-strict, strict)`, from one estimate and one
    /// pair of boundary parameters: the depth cell a segment ends in (strict at a column
    /// exit) and the one the next segment starts in (non-strict) share them.
    #[inline]
    fn cells_at(&self, i: usize, t: f32) -> (i32, i32) {
        let d = self.d[i];
        if d == 0.0 {
            let c = self.o[i].floor() as i32;
            return (c, c);
        }
        let step = if d > 0.0 { 1 } else { -1 };
        let c = (self.o[i] + t * d).floor() as i32;
        let e = self.enter_t(i, c);
        let e_next = self.enter_t(i, c + step);
        let loose = if e > t {
            c - step
        } else if e_next <= t {
            c + step
        } else {
            c
        };
        let strict = if e >= t {
            c - step
        } else if e_next < t {
            c + step
        } else {
            c
        };
        (loose, strict)
    }

    /// The half of the box `[lo, hi)` along axis `i` (halves `half` wide) that holds the ray
    /// at `t`: `lo + half` or `lo`. The same decision as `cell_at(i, t, false) ≥ lo + half`
    /// (the cell entered at or before `t` lies beyond the middle plane iff the ray has crossed
    /// it by `t`), from one boundary parameter; an upper half outside the grid (odd sizes)
    /// is never chosen, as clamping the cell into the box would not.
    #[inline]
    fn half_at(&self, i: usize, t: f32, lo: i32, hi: i32, half: i32) -> i32 {
        let mid = lo + half;
        let upper = if self.d[i] > 0.0 {
            boundary_t(mid as f32, self.o[i], self.inv[i]) <= t
        } else if self.d[i] < 0.0 {
            // Going down, the ray enters cell mid − 1 through plane `mid` (never NaN: the
            // origin and 1/d are finite).
            t < boundary_t(mid as f32, self.o[i], self.inv[i])
        } else {
            self.o[i].floor() as i32 >= mid
        };
        if upper && mid < hi {
            mid
        } else {
            lo
        }
    }

    /// Parameter where the ray leaves `[lo, hi)` along axis `i`; `+inf` if parallel.
    #[inline]
    fn exit_t(&self, i: usize, lo: i32, hi: i32) -> f32 {
        if self.d[i] == 0.0 {
            return f32::INFINITY;
        }
        let b = if self.d[i] > 0.0 { hi } else { lo };
        boundary_t(b as f32, self.o[i], self.inv[i])
    }

    /// Builds the caller-facing hit for voxel `v` entered at rebased parameter `t`.
    fn hit(&self, v: IVec3, t: f32, steps: u32) -> HitResult {
        HitResult {
            hit: true,
            voxel: v.as_uvec3(),
            t: (self.t_base + t) / self.scale,
            position: self.o + t * self.d,
            steps,
            ran_out: false,
        }
    }
}

/// First set voxel with depth index between `k_in` and `k_out` (inclusive, in ray order:
/// from `k_in` towards `k_out`) in texel `(x, y)` of `level`. One ray-mask LUT fetch and AND
/// per layer the range spans (thesis §5.3.2, Fig. 16); the nearest bit in ray order is the
/// voxel-accurate hit (§5.3.4).
#[inline]
fn first_in_range(level: &BitGrid, x: u32, y: u32, k_in: u32, k_out: u32) -> Option<u32> {
    let forward = k_in <= k_out;
    let (lo, hi) = (k_in.min(k_out), k_in.max(k_out));
    let (layer_lo, layer_hi) = (lo / COLUMN_BITS, hi / COLUMN_BITS);
    let mut i = 0;
    while i <= layer_hi - layer_lo {
        let layer = if forward { layer_lo + i } else { layer_hi - i };
        let base = layer * COLUMN_BITS;
        let a = lo.max(base) - base;
        let b = hi.min(base + COLUMN_BITS - 1) - base;
        // GPU: texelFetch(rayMaskLut, ivec2(a, b), 0) & texelFetch(bits, ivec3(x, y, layer), lvl)
        let m = col_and(column_mask(a, b), level.column(x, y, layer));
        if !col_is_empty(m) {
            let bit = if forward {
                col_lowest_bit(m)
            } else {
                col_highest_bit(m)
            };
            return bit.map(|b| base + b);
        }
        i += 1;
    }
    None
}

/// Depth range `(k_in, k_out)` in ray order of a segment within a column, clamped to the grid,
/// from the depth cells at its ends: `k_in` the cell at its start (non-strict), `k_out` the
/// cell at its end (strict at a column exit, whose cell belongs to the next column;
/// non-strict at the ray's end, which is visited). `None` if the segment covers no depth cell
/// (possible only for a zero-length segment).
#[inline]
fn depth_range(ray: &Ray, k_in: i32, k_out: i32) -> Option<(u32, u32)> {
    let last = ray.dims.z - 1;
    // Past the far depth face already: the segment is the single point where the ray leaves
    // the grid through it (its end), outside the half-open grid.
    if (ray.d.z > 0.0 && k_in > last) || (ray.d.z < 0.0 && k_in < 0) {
        return None;
    }
    // Otherwise clamping only undoes rounding of the entry point / the end on the far face.
    let k_in = k_in.clamp(0, last);
    let k_out = k_out.clamp(0, last);
    let empty = if ray.d.z >= 0.0 {
        k_out < k_in
    } else {
        k_out > k_in
    };
    if empty {
        None
    } else {
        Some((k_in as u32, k_out as u32))
    }
}

/// Hit parameter inside the hit voxel's column: the column entry `t_col` if the hit is in the
/// depth cell the segment starts in, else the entry into depth cell `k` along the ray (§5.3.4,
/// t solved along the ray). Same choice as the DDA, which enters a voxel by one step.
#[inline]
fn hit_t(ray: &Ray, t_col: f32, k_in: u32, k: u32) -> f32 {
    if ray.d.z == 0.0 || k == k_in {
        t_col
    } else {
        t_col.max(ray.enter_t(2, k as i32))
    }
}

/// Start cell of a rebased ray, clamped into the grid (the entry point may round to just
/// outside).
fn start_cell(ray: &Ray) -> IVec3 {
    IVec3::new(
        ray.cell_at(0, 0.0, false).clamp(0, ray.dims.x - 1),
        ray.cell_at(1, 0.0, false).clamp(0, ray.dims.y - 1),
        ray.cell_at(2, 0.0, false).clamp(0, ray.dims.z - 1),
    )
}

fn dims_of(bits: &BitGrid) -> UVec3 {
    UVec3::new(bits.res_x(), bits.res_y(), bits.depth())
}

fn point_query(bits: &BitGrid, origin: Vec3, v: IVec3, t: f32, p: Vec3) -> HitResult {
    let u = v.as_uvec3();
    if bits.get(u.x, u.y, u.z) {
        HitResult {
            hit: true,
            voxel: u,
            t,
            position: p,
            steps: 1,
            ran_out: false,
        }
    } else {
        HitResult::miss(origin, 1, false)
    }
}

/// First hit along `origin + t·dir`, `t ∈ [0, t_max]`, by hierarchical traversal of the OR
/// mip hierarchy (thesis §5.3.2, Fig. 17): at the current level take the column box the ray is
/// in, AND the ray mask of the segment inside it with the column; empty → step into the next
/// column, one level coarser if that column lies in another parent box; non-empty → one level
/// finer; non-empty at level 0 → hit.
pub fn first_hit_hierarchical(
    h: &BitHierarchy,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    params: &TraversalParams,
) -> HitResult {
    let base = h.base();
    let ray = match setup_ray(dims_of(base), origin, dir, t_max) {
        Setup::Miss => return HitResult::miss(origin, 0, false),
        Setup::Point(v, t, p) => return point_query(base, origin, v, t, p),
        Setup::Ray(r) => r,
    };
    let max_level = h.max_level();
    let mut level = params.start_level.min(max_level);
    // The column containing the ray at parameter `t`, exact to the current level (its lower
    // bits are refined on the way down), and the depth cell at `t`.
    let start = start_cell(&ray);
    let (mut cx, mut cy) = (start.x, start.y);
    let mut k_t = ray.cell_at(2, 0.0, false);
    let mut t = 0.0f32;
    let mut steps = 0u32;
    // The loop only decides; the hit or miss is built once after it (the GPU twin does so
    // because every SIMD lane would otherwise pay for building it on every iteration).
    let mut done = false;
    let mut hit = None;
    while steps < params.max_iterations {
        steps += 1;
        // Column box at `level`, in level-0 texel units, clipped to the grid (odd sizes).
        let size = 1i32 << level;
        let (lx, ly) = ((cx >> level) << level, (cy >> level) << level);
        let (hx, hy) = ((lx + size).min(ray.dims.x), (ly + size).min(ray.dims.y));
        // Slab exit through the x and y faces only: the box spans the whole depth, and the
        // depth faces are already part of `t_end` (the ray is clipped to the grid).
        let tx = ray.exit_t(0, lx, hx);
        let ty = ray.exit_t(1, ly, hy);
        let t_exit = tx.min(ty);
        let ends_here = t_exit > ray.t_end;
        let t_out = if ends_here { ray.t_end } else { t_exit };
        let (k_next, k_before) = ray.cells_at(2, t_out);
        let k_out = if ends_here { k_next } else { k_before };
        if let Some((k_in, k_out)) = depth_range(&ray, k_t, k_out) {
            let lvl = h.level(level);
            let (x, y) = ((cx >> level) as u32, (cy >> level) as u32);
            if let Some(k) = first_in_range(lvl, x, y, k_in, k_out) {
                if level == 0 {
                    (done, hit) = (true, Some((k, k_in)));
                    break;
                }
                // Possible hit somewhere in this box: refine to the quarter holding the ray
                // at `t`, same position.
                level -= 1;
                let half = 1i32 << level;
                cx = ray.half_at(0, t, lx, hx, half);
                cy = ray.half_at(1, t, ly, hy, half);
                continue;
            }
        }
        // Empty: the whole segment inside this box is free. Step into the neighbouring
        // column across the exit face(s) — both on an exact edge crossing.
        if ends_here {
            done = true;
            break;
        }
        if t_exit >= t {
            t = t_exit;
            k_t = k_next;
        }
        // The axis not crossed stays in this box's range: exact to this level, as needed.
        let nx = if tx == t_exit {
            if ray.d.x > 0.0 {
                hx
            } else {
                lx - 1
            }
        } else {
            cx
        };
        let ny = if ty == t_exit {
            if ray.d.y > 0.0 {
                hy
            } else {
                ly - 1
            }
        } else {
            cy
        };
        if nx < 0 || ny < 0 || nx >= ray.dims.x || ny >= ray.dims.y {
            done = true;
            break;
        }
        // One level coarser only if the step left the parent box. Inside it, the parent is
        // the box the traversal came down from (it holds set bits ahead, so testing it again
        // mostly hits and costs one more descent) or one whose earlier part was just cleared
        // at this level; either way the next sibling is the cheaper test.
        let up = level + 1;
        if up <= max_level && ((nx >> up) != (cx >> up) || (ny >> up) != (cy >> up)) {
            level = up;
        }
        (cx, cy) = (nx, ny);
    }
    match hit {
        Some((k, k_in)) => {
            let v = IVec3::new(cx, cy, k as i32);
            ray.hit(v, hit_t(&ray, t, k_in, k), steps)
        }
        None => HitResult::miss(origin, steps, !done),
    }
}

/// Whether the segment `a → b` (voxel space) is free of set voxels, by
/// [`first_hit_hierarchical`] with `t_max = 1`. Both end voxels count: apply the thesis's
/// offsets (§5.3.1) before calling. A ray that exceeds the iteration cap counts as visible, as
/// on the GPU (thesis §5.3.2).
pub fn visible(h: &BitHierarchy, a: Vec3, b: Vec3, params: &TraversalParams) -> bool {
    !first_hit_hierarchical(h, a, b - a, 1.0, params).hit
}

/// Ground truth: Amanatides–Woo walk over every level-0 voxel the ray visits, using the same
/// boundary decisions as [`first_hit_hierarchical`].
pub fn first_hit_dda(bits: &BitGrid, origin: Vec3, dir: Vec3, t_max: f32) -> HitResult {
    let ray = match setup_ray(dims_of(bits), origin, dir, t_max) {
        Setup::Miss => return HitResult::miss(origin, 0, false),
        Setup::Point(v, t, p) => return point_query(bits, origin, v, t, p),
        Setup::Ray(r) => r,
    };
    let mut c = start_cell(&ray);
    let mut t = 0.0f32;
    let mut steps = 0u32;
    // Every step moves at least one axis monotonically towards the grid's exit.
    let bound = (ray.dims.x + ray.dims.y + ray.dims.z + 3) as u32;
    while steps < bound {
        steps += 1;
        if bits.get(c.x as u32, c.y as u32, c.z as u32) {
            return ray.hit(c, t, steps);
        }
        let tn = [
            ray.exit_t(0, c.x, c.x + 1),
            ray.exit_t(1, c.y, c.y + 1),
            ray.exit_t(2, c.z, c.z + 1),
        ];
        let t_next = tn[0].min(tn[1]).min(tn[2]);
        if t_next > ray.t_end {
            break;
        }
        for i in 0..3 {
            if tn[i] == t_next {
                c[i] += if ray.d[i] > 0.0 { 1 } else { -1 };
            }
        }
        if c.cmplt(IVec3::ZERO).any() || c.cmpge(ray.dims).any() {
            break;
        }
        t = t.max(t_next);
    }
    HitResult::miss(origin, steps, false)
}

/// Uniform marching baseline (thesis §6.4.1, Fig. 26): `steps` equidistant samples over the part of
/// `[0, t_max]` inside the grid (sample i at fraction `(i + ½)/steps`); each tests the voxel
/// at the sample (`thick = false`, the 1-bit mask) or the voxels `k−1..=k+1` of its column
/// (`thick = true`, the 3-bit mask of Nichols et al. 2010, thicker in depth only).
fn march(
    bits: &BitGrid,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    steps: u32,
    thick: bool,
) -> HitResult {
    let ray = match setup_ray(dims_of(bits), origin, dir, t_max) {
        Setup::Miss => return HitResult::miss(origin, 0, false),
        Setup::Point(v, t, p) => return point_query(bits, origin, v, t, p),
        Setup::Ray(r) => r,
    };
    let dt = ray.t_end / steps.max(1) as f32;
    let last = ray.dims - 1;
    let mut i = 0;
    while i < steps {
        let t = (i as f32 + 0.5) * dt;
        let p = ray.o + t * ray.d;
        let v = p.floor().as_ivec3().clamp(IVec3::ZERO, last);
        let (x, y, k) = (v.x as u32, v.y as u32, v.z as u32);
        let found = if thick {
            // 3-bit mask in ray order: from the nearer neighbour along the ray.
            let (k_in, k_out) = if ray.d.z >= 0.0 {
                (k.saturating_sub(1), (k + 1).min(last.z as u32))
            } else {
                ((k + 1).min(last.z as u32), k.saturating_sub(1))
            };
            first_in_range(bits, x, y, k_in, k_out)
        } else if bits.get(x, y, k) {
            Some(k)
        } else {
            None
        };
        if let Some(k) = found {
            return ray.hit(IVec3::new(v.x, v.y, k as i32), t, i + 1);
        }
        i += 1;
    }
    HitResult::miss(origin, steps, false)
}

/// Uniform marching with the 1-bit mask (thesis §6.4.1). Misses thin surfaces between samples.
pub fn march_1bit(bits: &BitGrid, origin: Vec3, dir: Vec3, t_max: f32, steps: u32) -> HitResult {
    march(bits, origin, dir, t_max, steps, false)
}

/// Uniform marching with the thick 3-bit mask (thesis §6.4.1). Catches more surfaces than the
/// 1-bit version but can report false hits near surfaces (thesis Fig. 26).
pub fn march_3bit(bits: &BitGrid, origin: Vec3, dir: Vec3, t_max: f32, steps: u32) -> HitResult {
    march(bits, origin, dir, t_max, steps, true)
}

#[cfg(test)]
mod helper_tests {
    use super::*;

    /// Rays through a 40×24×200 grid from a fixed xorshift stream: random interior origins,
    /// directions with some components exactly 0, ±1 or tiny, as `setup_ray` builds them.
    fn rays() -> Vec<Ray> {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut f = move || {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        };
        let dims = UVec3::new(40, 24, 200);
        let mut out = Vec::new();
        while out.len() < 400 {
            let o = Vec3::new(f() * 40.0, f() * 24.0, f() * 200.0);
            let mut d = Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5);
            for i in 0..3 {
                match (f() * 8.0) as u32 {
                    0 => d[i] = 0.0,
                    1 => d[i] = 1.0,
                    _ => {}
                }
            }
            if let Setup::Ray(r) = setup_ray(dims, o, d, 300.0) {
                out.push(r);
            }
        }
        out
    }

    /// The parameters worth testing along a ray: random ones and every boundary parameter
    /// of the first cells on each axis, where strict and non-strict differ.
    fn params(r: &Ray) -> Vec<f32> {
        let mut t: Vec<f32> = (0..16).map(|k| r.t_end * k as f32 / 15.0).collect();
        for i in 0..3 {
            if r.d[i] != 0.0 {
                let c0 = r.cell_at(i, 0.0, false);
                let step = if r.d[i] > 0.0 { 1 } else { -1 };
                for k in 0..12 {
                    let e = r.enter_t(i, c0 + k * step);
                    if (0.0..=r.t_end).contains(&e) {
                        t.push(e);
                    }
                }
            }
        }
        t
    }

    #[test]
    fn cells_at_is_cell_at_both_ways() {
        for r in rays() {
            for t in params(&r) {
                for i in 0..3 {
                    let want = (r.cell_at(i, t, false), r.cell_at(i, t, true));
                    assert_eq!(r.cells_at(i, t), want, "axis {i} at t = {t}: {r:?}");
                }
            }
        }
    }

    /// `half_at` picks the half that clamping the non-strict cell into the box picks, for
    /// every aligned box on the ray's path at each level.
    #[test]
    fn half_at_is_the_clamped_cell_half() {
        for r in rays() {
            for t in params(&r) {
                for i in 0..2 {
                    let dim = r.dims[i];
                    let c = r.cell_at(i, t, false).clamp(0, dim - 1);
                    for level in 1..7 {
                        let size = 1i32 << level;
                        let lo = (c >> level) << level;
                        let hi = (lo + size).min(dim);
                        let half = size / 2;
                        let cell = r.cell_at(i, t, false).clamp(lo, hi - 1);
                        let want = if cell >= lo + half { lo + half } else { lo };
                        assert_eq!(
                            r.half_at(i, t, lo, hi, half),
                            want,
                            "axis {i} level {level} t {t}"
                        );
                    }
                }
            }
        }
    }
}

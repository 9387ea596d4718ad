// Hierarchical voxel ray test (Thiedemann 2010, §5.3; uniform marching §6.4.1), a line-by-line port of the CPU twin in
// src/voxel/traverse.rs (read its module doc for the conventions and the deviations from the
// thesis). Voxel space: origin + t*dir, t in [0, t_max]; bit convention of
// docs/ARCHITECTURE.md, "The voxel representation".
//
// The including shader defines, before including this file:
//   uvec4 vx_column(uint level, int x, int y, uint layer);  // OR-hierarchy texel
//   uvec4 vx_ray_mask(uint a, uint b);                       // 128x128 LUT, a <= b
//   bool  vx_voxel(int x, int y, int k);                      // level-0 bit (DDA, marching)
//
// Floating-point expressions that decide boundaries are `precise` (no fma contraction), so
// the GPU takes exactly the CPU's decisions where division is correctly rounded.
#ifndef VOXEL_TRAVERSE_GLSL
#define VOXEL_TRAVERSE_GLSL

#define VX_COLUMN_BITS 128u
const float VX_DIR_EPS = 1e-12;
#define VX_INF uintBitsToFloat(0x7f800000u)

struct VxRay {
    vec3 o;        // entry point into the grid
    vec3 d;        // direction, largest component +-1, tiny components exactly 0
    vec3 inv;      // 1/d, 0 where d is 0
    float t_end;   // segment end (rebased, scaled parameter)
    float t_base;  // scaled parameter of the entry point
    float scale;   // largest |component| of the caller's direction
    ivec3 dims;
};

struct VxHit {
    bool hit;
    uvec3 voxel;
    float t;        // caller's parameter; +inf on a miss
    vec3 position;  // voxel-space point at t
    uint steps;
    bool ran_out;
};

VxHit vx_miss(vec3 origin, uint steps, bool ran_out) {
    bool finite = !any(isnan(origin)) && !any(isinf(origin));
    return VxHit(false, uvec3(0), VX_INF, finite ? origin : vec3(0.0), steps, ran_out);
}

float vx_boundary_t(float b, float o, float inv) {
    precise float r = (b - o) * inv;
    return r;
}

float vx_enter_t(VxRay r, int i, int c) {
    precise float b = r.d[i] > 0.0 ? float(c) : float(c) + 1.0;
    return vx_boundary_t(b, r.o[i], r.inv[i]);
}

int vx_cell_at(VxRay r, int i, float t, bool strict) {
    float d = r.d[i];
    if (d == 0.0) return int(floor(r.o[i]));
    int step_ = d > 0.0 ? 1 : -1;
    precise float p = r.o[i] + t * d;
    int c = int(floor(p));
    float e = vx_enter_t(r, i, c);
    if (e > t || (strict && e == t)) {
        c -= step_;
    } else {
        float en = vx_enter_t(r, i, c + step_);
        if (en < t || (!strict && en == t)) c += step_;
    }
    return c;
}

// vx_cell_at at t both ways: x non-strict, y strict (one estimate, one boundary pair).
ivec2 vx_cells_at(VxRay r, int i, float t) {
    float d = r.d[i];
    if (d == 0.0) return ivec2(int(floor(r.o[i])));
    int step_ = d > 0.0 ? 1 : -1;
    precise float p = r.o[i] + t * d;
    int c = int(floor(p));
    float e = vx_enter_t(r, i, c);
    float en = vx_enter_t(r, i, c + step_);
    int loose = e > t ? c - step_ : (en <= t ? c + step_ : c);
    int strict_ = e >= t ? c - step_ : (en < t ? c + step_ : c);
    return ivec2(loose, strict_);
}

// The half (lo + half or lo) of the box [lo, hi) along axis i holding the ray at t.
int vx_half_at(VxRay r, int i, float t, int lo, int hi, int half_) {
    int mid = lo + half_;
    bool upper;
    if (r.d[i] > 0.0) upper = vx_boundary_t(float(mid), r.o[i], r.inv[i]) <= t;
    else if (r.d[i] < 0.0) upper = t < vx_boundary_t(float(mid), r.o[i], r.inv[i]);
    else upper = int(floor(r.o[i])) >= mid;
    return upper && mid < hi ? mid : lo;
}

float vx_exit_t(VxRay r, int i, int lo, int hi) {
    if (r.d[i] == 0.0) return VX_INF;
    return vx_boundary_t(r.d[i] > 0.0 ? float(hi) : float(lo), r.o[i], r.inv[i]);
}

VxHit vx_make_hit(VxRay r, ivec3 v, float t, uint steps) {
    precise vec3 p = r.o + t * r.d;
    precise float tc = (r.t_base + t) / r.scale;
    return VxHit(true, uvec3(v), tc, p, steps, false);
}

#define VX_SETUP_MISS 0
#define VX_SETUP_POINT 1
#define VX_SETUP_RAY 2

// Scales, guards, clips and rebases a ray. On VX_SETUP_POINT, (pv, pt, pp) is the single
// voxel, caller parameter and point that the degenerate ray visits.
int vx_setup(ivec3 dims, vec3 origin, vec3 dir, float t_max, out VxRay r, out ivec3 pv, out float pt, out vec3 pp) {
    r = VxRay(vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 0.0, 1.0, dims);
    pv = ivec3(0);
    pt = 0.0;
    pp = vec3(0.0);
    if (any(isnan(origin)) || any(isinf(origin)) || any(isnan(dir)) || any(isinf(dir)) || isnan(t_max) || t_max < 0.0)
        return VX_SETUP_MISS;
    vec3 dims_f = vec3(dims);
    float scale = max(max(abs(dir.x), abs(dir.y)), abs(dir.z));
    if (scale == 0.0) {
        if (all(greaterThanEqual(origin, vec3(0.0))) && all(lessThan(origin, dims_f))) {
            pv = ivec3(floor(origin));
            pp = origin;
            return VX_SETUP_POINT;
        }
        return VX_SETUP_MISS;
    }
    vec3 d = dir / scale;
    vec3 inv = vec3(0.0);
    float t0 = 0.0;
    precise float t_lim = t_max * scale;
    float t1 = t_lim;
    for (int i = 0; i < 3; ++i) {
        if (abs(d[i]) < VX_DIR_EPS) {
            d[i] = 0.0;
            if (!(origin[i] >= 0.0 && origin[i] < dims_f[i])) return VX_SETUP_MISS;
        } else {
            inv[i] = 1.0 / d[i];
            float ta = vx_boundary_t(0.0, origin[i], inv[i]);
            float tb = vx_boundary_t(dims_f[i], origin[i], inv[i]);
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    if (t0 > t1) return VX_SETUP_MISS;
    precise vec3 o = origin + t0 * d;
    precise float t_end = t_lim - t0;
    for (int i = 0; i < 3; ++i) {
        if (d[i] != 0.0) {
            float ta = vx_boundary_t(0.0, o[i], inv[i]);
            float tb = vx_boundary_t(dims_f[i], o[i], inv[i]);
            t_end = min(t_end, max(ta, tb));
        }
    }
    r = VxRay(o, d, inv, max(t_end, 0.0), t0, scale, dims);
    if (r.t_end > 0.0) return VX_SETUP_RAY;
    ivec3 c = ivec3(vx_cell_at(r, 0, 0.0, false), vx_cell_at(r, 1, 0.0, false), vx_cell_at(r, 2, 0.0, false));
    if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, dims))) return VX_SETUP_MISS;
    pv = c;
    pt = r.t_base / scale;
    pp = o;
    return VX_SETUP_POINT;
}

uint vx_lowest_bit(uvec4 m) {
    if (m.x != 0u) return uint(findLSB(m.x));
    if (m.y != 0u) return 32u + uint(findLSB(m.y));
    if (m.z != 0u) return 64u + uint(findLSB(m.z));
    return 96u + uint(findLSB(m.w));
}

uint vx_highest_bit(uvec4 m) {
    if (m.w != 0u) return 96u + uint(findMSB(m.w));
    if (m.z != 0u) return 64u + uint(findMSB(m.z));
    if (m.y != 0u) return 32u + uint(findMSB(m.y));
    return uint(findMSB(m.x));
}

// First set voxel with depth in [k_in, k_out] in ray order in texel (x, y) of `level`:
// one ray-mask LUT fetch and AND per layer the range spans (thesis §5.3.2, §5.3.4).
bool vx_first_in_range(uint level, int x, int y, uint k_in, uint k_out, out uint k) {
    bool forward = k_in <= k_out;
    uint lo = min(k_in, k_out), hi = max(k_in, k_out);
    uint layer_lo = lo / VX_COLUMN_BITS, layer_hi = hi / VX_COLUMN_BITS;
    k = 0u;
    for (uint i = 0u; i <= layer_hi - layer_lo; ++i) {
        uint layer = forward ? layer_lo + i : layer_hi - i;
        uint base = layer * VX_COLUMN_BITS;
        uint a = max(lo, base) - base;
        uint b = min(hi, base + VX_COLUMN_BITS - 1u) - base;
        uvec4 m = vx_ray_mask(a, b) & vx_column(level, x, y, layer);
        if (any(notEqual(m, uvec4(0u)))) {
            k = base + (forward ? vx_lowest_bit(m) : vx_highest_bit(m));
            return true;
        }
    }
    return false;
}

bool vx_depth_range(VxRay r, int k_in, int k_out, out uint k_in_out, out uint k_out_out) {
    int last = r.dims.z - 1;
    k_in_out = 0u;
    k_out_out = 0u;
    if ((r.d.z > 0.0 && k_in > last) || (r.d.z < 0.0 && k_in < 0)) return false;
    k_in = clamp(k_in, 0, last);
    k_out = clamp(k_out, 0, last);
    bool empty = r.d.z >= 0.0 ? k_out < k_in : k_out > k_in;
    k_in_out = uint(k_in);
    k_out_out = uint(k_out);
    return !empty;
}

float vx_hit_t(VxRay r, float t_col, uint k_in, uint k) {
    if (r.d.z == 0.0 || k == k_in) return t_col;
    return max(t_col, vx_enter_t(r, 2, int(k)));
}

ivec3 vx_start_cell(VxRay r) {
    return ivec3(clamp(vx_cell_at(r, 0, 0.0, false), 0, r.dims.x - 1),
                 clamp(vx_cell_at(r, 1, 0.0, false), 0, r.dims.y - 1),
                 clamp(vx_cell_at(r, 2, 0.0, false), 0, r.dims.z - 1));
}

VxHit vx_point_query(vec3 origin, ivec3 v, float t, vec3 p) {
    if (vx_voxel(v.x, v.y, v.z)) return VxHit(true, uvec3(v), t, p, 1u, false);
    return vx_miss(origin, 1u, false);
}

// First hit along origin + t*dir by hierarchical traversal of the OR mip hierarchy (§5.3.2).
VxHit voxel_first_hit(ivec3 dims, uint max_level, vec3 origin, vec3 dir, float t_max, uint start_level, uint max_iterations) {
    VxRay r;
    ivec3 pv;
    float pt;
    vec3 pp;
    int s = vx_setup(dims, origin, dir, t_max, r, pv, pt, pp);
    if (s == VX_SETUP_MISS) return vx_miss(origin, 0u, false);
    if (s == VX_SETUP_POINT) return vx_point_query(origin, pv, pt, pp);
    uint level = min(start_level, max_level);
    ivec3 start = vx_start_cell(r);
    int cx = start.x, cy = start.y;  // exact to the current level
    int k_t = vx_cell_at(r, 2, 0.0, false);
    float t = 0.0;
    uint steps = 0u;
    // The loop only decides; the hit or miss is built once after it (on a SIMD device every
    // lane would otherwise pay for building it on every iteration).
    bool done = false, hit = false;
    uint hit_k = 0u, hit_k_in = 0u;
    while (steps < max_iterations) {
        steps += 1u;
        int size = 1 << level;
        int lx = (cx >> level) << level, ly = (cy >> level) << level;
        int hx = min(lx + size, r.dims.x), hy = min(ly + size, r.dims.y);
        float tx = vx_exit_t(r, 0, lx, hx);
        float ty = vx_exit_t(r, 1, ly, hy);
        float t_exit = min(tx, ty);
        bool ends_here = t_exit > r.t_end;
        float t_out = ends_here ? r.t_end : t_exit;
        ivec2 kk = vx_cells_at(r, 2, t_out);
        uint k_in, k_out;
        if (vx_depth_range(r, k_t, ends_here ? kk.x : kk.y, k_in, k_out)) {
            uint k;
            if (vx_first_in_range(level, cx >> level, cy >> level, k_in, k_out, k)) {
                if (level == 0u) {
                    done = hit = true;
                    hit_k = k;
                    hit_k_in = k_in;
                    break;
                }
                level -= 1u;
                int half_ = 1 << level;
                cx = vx_half_at(r, 0, t, lx, hx, half_);
                cy = vx_half_at(r, 1, t, ly, hy, half_);
                continue;
            }
        }
        if (ends_here) {
            done = true;
            break;
        }
        if (t_exit >= t) {
            t = t_exit;
            k_t = kk.x;
        }
        int nx = tx == t_exit ? (r.d.x > 0.0 ? hx : lx - 1) : cx;
        int ny = ty == t_exit ? (r.d.y > 0.0 ? hy : ly - 1) : cy;
        if (nx < 0 || ny < 0 || nx >= r.dims.x || ny >= r.dims.y) {
            done = true;
            break;
        }
        // One level coarser only if the step left the parent box (see the CPU twin).
        uint up = level + 1u;
        if (up <= max_level && ((nx >> up) != (cx >> up) || (ny >> up) != (cy >> up))) level = up;
        cx = nx;
        cy = ny;
    }
    if (hit) return vx_make_hit(r, ivec3(cx, cy, int(hit_k)), vx_hit_t(r, t, hit_k_in, hit_k), steps);
    return vx_miss(origin, steps, !done);
}

// Whether the segment a -> b (voxel space) is free of set voxels (both end voxels count:
// apply the thesis's offsets, §5.3.1, first). Running out of iterations counts as visible.
bool voxel_visible(ivec3 dims, uint max_level, vec3 a, vec3 b, uint start_level, uint max_iterations) {
    return !voxel_first_hit(dims, max_level, a, b - a, 1.0, start_level, max_iterations).hit;
}

// Ground truth: Amanatides-Woo walk over level 0 with the same boundary decisions.
VxHit voxel_first_hit_dda(ivec3 dims, vec3 origin, vec3 dir, float t_max) {
    VxRay r;
    ivec3 pv;
    float pt;
    vec3 pp;
    int s = vx_setup(dims, origin, dir, t_max, r, pv, pt, pp);
    if (s == VX_SETUP_MISS) return vx_miss(origin, 0u, false);
    if (s == VX_SETUP_POINT) return vx_point_query(origin, pv, pt, pp);
    ivec3 c = vx_start_cell(r);
    float t = 0.0;
    uint steps = 0u;
    uint bound = uint(r.dims.x + r.dims.y + r.dims.z + 3);
    while (steps < bound) {
        steps += 1u;
        if (vx_voxel(c.x, c.y, c.z)) return vx_make_hit(r, c, t, steps);
        vec3 tn = vec3(vx_exit_t(r, 0, c.x, c.x + 1), vx_exit_t(r, 1, c.y, c.y + 1), vx_exit_t(r, 2, c.z, c.z + 1));
        float t_next = min(min(tn.x, tn.y), tn.z);
        if (t_next > r.t_end) break;
        for (int i = 0; i < 3; ++i)
            if (tn[i] == t_next) c[i] += r.d[i] > 0.0 ? 1 : -1;
        if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, r.dims))) break;
        t = max(t, t_next);
    }
    return vx_miss(origin, steps, false);
}

// Uniform marching baseline (§6.4.1): `samples` equidistant samples; each tests its voxel
// (thick = false, 1-bit mask) or the voxels k-1..k+1 of its column (thick = true, 3-bit).
VxHit voxel_march(ivec3 dims, vec3 origin, vec3 dir, float t_max, uint samples, bool thick) {
    VxRay r;
    ivec3 pv;
    float pt;
    vec3 pp;
    int s = vx_setup(dims, origin, dir, t_max, r, pv, pt, pp);
    if (s == VX_SETUP_MISS) return vx_miss(origin, 0u, false);
    if (s == VX_SETUP_POINT) return vx_point_query(origin, pv, pt, pp);
    precise float dt = r.t_end / float(max(samples, 1u));
    ivec3 last = r.dims - 1;
    for (uint i = 0u; i < samples; ++i) {
        precise float t = (float(i) + 0.5) * dt;
        precise vec3 p = r.o + t * r.d;
        ivec3 v = clamp(ivec3(floor(p)), ivec3(0), last);
        bool found;
        uint k = uint(v.z);
        if (thick) {
            uint kz = uint(v.z), lz = uint(last.z);
            uint k_in = r.d.z >= 0.0 ? (kz > 0u ? kz - 1u : 0u) : min(kz + 1u, lz);
            uint k_out = r.d.z >= 0.0 ? min(kz + 1u, lz) : (kz > 0u ? kz - 1u : 0u);
            found = vx_first_in_range(0u, v.x, v.y, k_in, k_out, k);
        } else {
            found = vx_voxel(v.x, v.y, v.z);
        }
        if (found) return vx_make_hit(r, ivec3(v.x, v.y, int(k)), t, i + 1u);
    }
    return vx_miss(origin, samples, false);
}

#endif

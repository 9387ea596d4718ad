// The exact conservative triangle voxelizer shared by `voxelize_triangles.comp` (bits) and
// `voxelize_attributes.comp` (albedo and normal volumes), so both set exactly the same voxels.
// The including shader declares `tris` (struct Triangle with vec4 v[3]), the push constants
// `pc` of voxelize_triangles.comp, the hooks VOXEL_COLUMN_BEGIN(x, y), VOXEL_HIT(x, y, k) and
// VOXEL_COLUMN_END(x, y), and VOXEL_COVERAGE(t): the triangle's (1 - opacity, object seed)
// as a vec2 (voxel_coverage.glsl); it calls voxelize_triangle_core() from main. A touched
// voxel is a hit where the coverage hash sets it (always for opaque triangles).
//
// Exactness: the f32 operations are those of the reference in the same order. Every value
// that mixes products and sums is `precise`, so no fused multiply-add is contracted (Vulkan
// guarantees correctly rounded +, -, *; division and sqrt only bound the per-column depth
// range, widened by a voxel, and never decide a bit).
#ifndef VOXELIZE_CORE_GLSL
#define VOXELIZE_CORE_GLSL

#include "voxel_coverage.glsl"

// f32 bit pattern of DEGENERATE_REL = 1e-9 in voxelize.rs (a literal could round twice).
#define DEGENERATE_REL uintBitsToFloat(0x3089705fu)

float dot_exact(vec3 a, vec3 b) {
    precise float r = (a.x * b.x) + (a.y * b.y) + (a.z * b.z);
    return r;
}

vec3 cross_exact(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
    return r;
}

bool is_degenerate(vec3 e0, vec3 e1, vec3 n) {
    precise float l = dot_exact(n, n);
    precise float bound = DEGENERATE_REL * dot_exact(e0, e0) * dot_exact(e1, e1);
    return l <= bound;
}

#include "voxel_space.glsl"

const vec3 HALF = vec3(0.5);

const vec3 X_AXIS = vec3(1.0, 0.0, 0.0);
const vec3 Y_AXIS = vec3(0.0, 1.0, 0.0);
const vec3 Z_AXIS = vec3(0.0, 0.0, 1.0);

// Whether the axis unit x edge separates the triangle v0 v1 v2 from the box [-HALF, HALF]
// (the same operations, in the same order, as the CPU reference).
bool separates(vec3 unit, vec3 edge, vec3 v0, vec3 v1, vec3 v2) {
    vec3 axis = cross_exact(unit, edge);
    float p0 = dot_exact(axis, v0);
    float p1 = dot_exact(axis, v1);
    float p2 = dot_exact(axis, v2);
    float rad = dot_exact(HALF, abs(axis));
    float pmin = min(min(p0, p1), p2);
    float pmax = max(max(p0, p1), p2);
    return pmin > rad || pmax < -rad;
}

bool tri_box_overlap(vec3 center, vec3 t0, vec3 t1, vec3 t2) {
    precise vec3 v0 = t0 - center;
    precise vec3 v1 = t1 - center;
    precise vec3 v2 = t2 - center;
    vec3 lo = min(min(v0, v1), v2);
    vec3 hi = max(max(v0, v1), v2);
    if (any(greaterThan(lo, HALF)) || any(lessThan(hi, -HALF))) {
        return false;
    }
    precise vec3 edges[3] = vec3[3](v1 - v0, v2 - v1, v0 - v2);
    // The nine edge x axis tests written out: lavapipe counts loop iterations against a
    // per-invocation budget (see voxelize_loads in gpu.rs) and runs loops slowly.
    if (separates(X_AXIS, edges[0], v0, v1, v2) || separates(Y_AXIS, edges[0], v0, v1, v2)
        || separates(Z_AXIS, edges[0], v0, v1, v2) || separates(X_AXIS, edges[1], v0, v1, v2)
        || separates(Y_AXIS, edges[1], v0, v1, v2) || separates(Z_AXIS, edges[1], v0, v1, v2)
        || separates(X_AXIS, edges[2], v0, v1, v2) || separates(Y_AXIS, edges[2], v0, v1, v2)
        || separates(Z_AXIS, edges[2], v0, v1, v2)) {
        return false;
    }
    vec3 n = cross_exact(edges[0], edges[1]);
    if (is_degenerate(edges[0], edges[1], n)) {
        return true;
    }
    float d = dot_exact(n, v0);
    float r = dot_exact(HALF, abs(n));
    precise float below = d - r;
    precise float above = d + r;
    return below <= 0.0 && above >= 0.0;
}

void voxelize_triangle_core() {
    uint tri_index = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (tri_index >= pc.extent.z) {
        return;
    }
    Triangle t = tris[pc.extent.w + tri_index];
    vec3 a = to_voxel(t.v[0].xyz);
    vec3 b = to_voxel(t.v[1].xyz);
    vec3 c = to_voxel(t.v[2].xyz);
    vec2 coverage = VOXEL_COVERAGE(t);
    uint seed = uint(coverage.y);
    vec3 dims_f = vec3(pc.dims.xyz);
    vec3 lo = min(min(a, b), c);
    vec3 hi = max(max(a, b), c);
    // Closed boxes: a vertex at exactly x = 3 touches voxels 2 and 3.
    if (any(lessThan(hi, vec3(0.0))) || any(greaterThan(lo, dims_f))) {
        return;
    }
    precise vec3 e0 = b - a;
    precise vec3 e1 = c - b;
    vec3 n = cross_exact(e0, e1);
    bool degenerate = is_degenerate(e0, e1, n);
    uvec3 first = uvec3(clamp(ceil(lo) - 1.0, vec3(0.0), dims_f - 1.0));
    uvec3 last = uvec3(clamp(floor(hi), vec3(0.0), dims_f - 1.0));
    // Per column, the plane bounds the depth range where it is not steep (a pure speed-up:
    // widened by a voxel; the SAT test decides every bit).
    bool use_plane = !degenerate && abs(n.z) >= 0.1 * sqrt(dot_exact(n, n));
    uint w = last.x - first.x + 1u;
    uint columns = w * (last.y - first.y + 1u);
    // Lavapipe ends every loop of an invocation once 65,535 iterations of all its loops have
    // run (LP_MAX_TGSI_LOOP_ITERATIONS), silently. So the dispatch's z workgroups split each
    // triangle's columns, as many as its largest triangle needs to stay within that budget
    // (src/voxel/gpu.rs, voxelize_loads).
    uint stride = gl_WorkGroupSize.x * gl_NumWorkGroups.z;
    for (uint col = gl_WorkGroupID.z * gl_WorkGroupSize.x + gl_LocalInvocationIndex;
         col < columns; col += stride) {
        uint x = first.x + col % w;
        uint y = first.y + col / w;
        uint k0 = first.z;
        uint k1 = last.z;
        if (use_plane) {
            float x0 = float(x), x1 = float(x) + 1.0, y0 = float(y), y1 = float(y) + 1.0;
            vec4 zs = vec4(a.z) - (n.x * (vec4(x0, x1, x0, x1) - a.x)
                                   + n.y * (vec4(y0, y0, y1, y1) - a.y)) / n.z;
            float zmin = min(min(zs.x, zs.y), min(zs.z, zs.w)) - 1.0;
            float zmax = max(max(zs.x, zs.y), max(zs.z, zs.w)) + 1.0;
            k0 = max(k0, uint(clamp(floor(zmin), 0.0, dims_f.z - 1.0)));
            k1 = min(k1, uint(clamp(floor(zmax), 0.0, dims_f.z - 1.0)));
        }
        VOXEL_COLUMN_BEGIN(x, y)
        for (uint k = k0; k <= k1; ++k) {
            vec3 center = vec3(float(x), float(y), float(k)) + HALF;
            if (tri_box_overlap(center, a, b, c)
                && coverage_covers(uvec3(x, y, k), coverage.x, seed)) {
                VOXEL_HIT(x, y, k)
            }
        }
        VOXEL_COLUMN_END(x, y)
    }
}

#endif

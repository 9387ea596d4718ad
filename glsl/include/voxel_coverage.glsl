// Stochastic coverage of surfaces with opacity below 1 in the voxel grid: the GPU twin of
// src/voxel/coverage.rs (the same integer hash, the same comparison, so the same voxels). A
// triangle carries its coverage in the w components of its first two vertices: v[0].w = 1 -
// opacity (0 = opaque, no decision), v[1].w = the object's seed (an integer below 2^24).
// A voxel (x, y, depth index) the triangle touches is set where the hash of its cell (8^3
// voxels, so that a ray crossing a thin pane obliquely mostly meets one decision) is at least
// 1 - opacity.
#ifndef VOXEL_COVERAGE_GLSL
#define VOXEL_COVERAGE_GLSL

// log2 of CELL_VOXELS in coverage.rs.
#define COVERAGE_CELL_SHIFT 3u

// PCG (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering", the `pcg` listing).
uint coverage_pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Whether a triangle of `transparency` (1 - opacity) and `seed` sets voxel v.
bool coverage_covers(uvec3 v, float transparency, uint seed) {
    if (transparency <= 0.0) {
        return true;
    }
    uvec3 c = v >> COVERAGE_CELL_SHIFT;
    uint h = coverage_pcg(c.x + coverage_pcg(c.y + coverage_pcg(c.z + coverage_pcg(seed))));
    return float(h >> 8u) * (1.0 / 16777216.0) >= transparency;
}

// The atlas voxelizer's passes (voxelize_atlas.comp, voxelize_atlas_bits.vert,
// voxelize_atlas_volumes.vert) define ATLAS_COVERAGE_BINDING: their points carry a triangle
// index, not a triangle, so an instance whose object has a surface of opacity below 1 binds
// its per-triangle coverage there (src/voxel/gpu_atlas.rs, AtlasCoverage: per triangle
// vec2(1 - opacity, seed), the values the triangle voxelizer reads from v[0].w and v[1].w).
// An opaque instance binds its point chunk instead and passes `has_coverage` = 0 (the push
// constants' extent.w), so the buffer is never read and every point sets its voxel.
#ifdef ATLAS_COVERAGE_BINDING
layout(set = 0, binding = ATLAS_COVERAGE_BINDING, std430) readonly buffer AtlasCoverage {
    vec2 atlas_coverage[];
};

// Whether the point of triangle `tri` in voxel v sets it: the triangle voxelizer's test.
bool atlas_point_covers(uvec3 v, uint tri, uint has_coverage) {
    if (has_coverage == 0u) {
        return true;
    }
    vec2 c = atlas_coverage[tri];
    return coverage_covers(v, c.x, uint(c.y));
}
#endif

#endif

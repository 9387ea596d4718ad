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

#endif

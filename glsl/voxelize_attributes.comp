#version 450
// Albedo and normal volumes congruent with the bit grid (docs/ARCHITECTURE.md, "The voxel
// representation"), for methods that need more than occupancy (the voxel path tracer), step 1 of 2.
// The same exact conservative triangle test as voxelize_triangles.comp visits the same voxels; each
// voxel keeps the smallest index of the triangles that set it (atomicMin; a triangle of opacity
// below 1 sets only the voxels its coverage hash keeps, as in the bits), so where triangles
// share a voxel the result does not depend on the order the GPU runs them in.
// voxelize_attributes_resolve.comp then writes that triangle's albedo and normal.
#include "voxel_bits.glsl"

layout(local_size_x_id = 0) in;

struct Triangle {
    vec4 v[3];   // world-space vertices; w of v[0..2] = the material's albedo r, g, b
    vec4 coverage;   // x = 1 - opacity, y = the object's coverage seed (voxel_coverage.glsl)
};
layout(set = 0, binding = 0, std430) readonly buffer Triangles { Triangle tris[]; };
layout(set = 0, binding = 1, r32ui) uniform uimage3D owner_volume;

layout(push_constant) uniform Push {
    vec4 grid_min;
    vec4 scale;
    uvec4 dims;
    uvec4 extent;
} pc;

#define VOXEL_COLUMN_BEGIN(x, y)
#define VOXEL_HIT(x, y, k) \
    { imageAtomicMin(owner_volume, ivec3(x, y, k), pc.extent.w + tri_index); }
#define VOXEL_COLUMN_END(x, y)
#define VOXEL_COVERAGE(t) t.coverage.xy
#include "voxelize_core.glsl"

void main() {
    voxelize_triangle_core();
}

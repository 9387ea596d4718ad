#version 450
// Atlas voxelization (Thiedemann 2010, §4.3.1): one point per valid atlas texel, transformed by the
// object's model matrix and the voxel camera, sets its voxel's bit. The bits go into the
// same column buffer as voxelize_triangles (atomicOr) instead of an RGBA32UI target with
// logicOp OR, so both voxelizers share voxel_clear / voxel_copy_static / voxel_store. A point
// on a surface of opacity below 1 sets its voxel where the triangle voxelizer's stochastic
// coverage keeps it (voxel_coverage.glsl).
#include "voxel_bits.glsl"
#include "atlas_voxel.glsl"
#define ATLAS_COVERAGE_BINDING 2
#include "voxel_coverage.glsl"

layout(local_size_x = 64) in;

// Per point its model-space position's f32 bits and its triangle's index (atlas_points.comp).
layout(set = 0, binding = 0, std430) readonly buffer Points { uvec4 points[]; };
layout(set = 0, binding = 1, std430) buffer Columns { uint words[]; };

layout(push_constant) uniform Push {
    mat4 model;      // model → world
    vec4 grid_min;   // world corner of the grid box (xyz)
    vec4 scale;      // voxels per meter in the voxel-camera frame (u, v, w)
    uvec4 dims;      // res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)
    uvec4 extent;    // column-buffer width, height; point count; 1: coverage bound
} pc;

void main() {
    uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x)
           + gl_GlobalInvocationID.x;
    if (i >= pc.extent.z) {
        return;
    }
    uvec4 pt = points[i];
    uvec3 u;
    if (!atlas_point_voxel(pc.model, uintBitsToFloat(pt.xyz), pc.grid_min.xyz, pc.scale.xyz,
                           pc.dims, u)
        || !atlas_point_covers(u, pt.w, pc.extent.w)) {
        return;
    }
    atomicOr(words[voxel_word_index(u.xy, u.z, pc.extent.xy)], 1u << voxel_bit(u.z));
}

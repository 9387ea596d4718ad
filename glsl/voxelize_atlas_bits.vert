#version 450
// The thesis's binary atlas voxelization as a raster pass (Thiedemann 2010, §4.3.1): one vertex per atlas
// point, drawn as a point list into the R32G32B32A32_UINT column image. The point's voxel
// comes from atlas_voxel.glsl, as in the compute twin voxelize_atlas.comp, so both set the
// same bits (a point its surface's coverage drops among them); its raster position is its column's centre (viewport = the image's extent).
#include "atlas_voxel.glsl"
#define ATLAS_COVERAGE_BINDING 2
#include "voxel_coverage.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Points { uvec4 points[]; };

layout(push_constant) uniform Push {
    mat4 model;      // model -> world
    vec4 grid_min;   // world corner of the grid box (xyz)
    vec4 scale;      // voxels per meter in the voxel-camera frame (u, v, w)
    uvec4 dims;      // res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)
    uvec4 extent;    // column image width, height; point count; 1: coverage bound
} pc;

layout(location = 0) flat out int v_depth;   // depth index k, -1 outside the grid

void main() {
    uvec4 pt = points[gl_VertexIndex];
    uvec3 voxel;
    bool inside = atlas_point_voxel(pc.model, uintBitsToFloat(pt.xyz), pc.grid_min.xyz,
                                    pc.scale.xyz, pc.dims, voxel)
               && atlas_point_covers(voxel, pt.w, pc.extent.w);
    v_depth = inside ? int(voxel.z) : -1;
    vec2 ndc = (vec2(voxel.xy) + 0.5) / vec2(pc.extent.xy) * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.5, 1.0);
}

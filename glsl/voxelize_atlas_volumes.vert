#version 450
// Non-binary atlas voxelization (Thiedemann 2010, §4.3.2): one vertex per atlas point (vertex pulling, no
// vertex buffer), drawn as a point list. The point goes to the same voxel as its bit in
// voxelize_atlas.comp (atlas_voxel.glsl); its raster position is that voxel's column centre
// (the viewport is the grid's x,y resolution) and the geometry shader routes it to the layer
// of its depth index. It carries its triangle's material albedo and world-space face normal,
// computed like voxelize_attributes.comp so both voxelizers feed the path tracer alike.
#include "atlas_voxel.glsl"

struct Triangle {
    vec4 v[3];   // model-space vertices; w of v[0..2] = the material's albedo r, g, b
};
layout(set = 0, binding = 0, std430) readonly buffer Points { uvec4 points[]; };
layout(set = 0, binding = 1, std430) readonly buffer Triangles { Triangle tris[]; };

layout(push_constant) uniform Push {
    mat4 model;      // model -> world
    vec4 grid_min;   // world corner of the grid box (xyz)
    vec4 scale;      // voxels per meter in the voxel-camera frame (u, v, w)
    uvec4 dims;      // res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)
    uvec4 extent;    // unused here (column-buffer size and point count of the compute twin)
} pc;

layout(location = 0) flat out int v_layer;   // depth index k, -1 outside the grid
layout(location = 1) flat out vec3 v_albedo;
layout(location = 2) flat out vec3 v_normal;

void main() {
    uvec4 pt = points[gl_VertexIndex];
    uvec3 voxel;
    bool inside = atlas_point_voxel(pc.model, uintBitsToFloat(pt.xyz), pc.grid_min.xyz,
                                    pc.scale.xyz, pc.dims, voxel);
    v_layer = inside ? int(voxel.z) : -1;
    // The column centre: a size-1 point there covers exactly pixel (voxel.x, voxel.y).
    vec2 ndc = (vec2(voxel.xy) + 0.5) / vec2(pc.dims.xy) * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.5, 1.0);
    Triangle t = tris[pt.w];
    vec3 w0 = (pc.model * vec4(t.v[0].xyz, 1.0)).xyz;
    vec3 w1 = (pc.model * vec4(t.v[1].xyz, 1.0)).xyz;
    vec3 w2 = (pc.model * vec4(t.v[2].xyz, 1.0)).xyz;
    vec3 n = cross(w1 - w0, w2 - w0);
    v_normal = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    v_albedo = vec3(t.v[0].w, t.v[1].w, t.v[2].w);
}

#version 450
// Albedo and normal volumes congruent with the bit grid (DESIGN.md "Voxel representation"),
// for methods that need more than occupancy (the voxel path tracer). The same exact
// conservative triangle test as voxelize_triangles.comp sets the same voxels; each stores its
// triangle's albedo and world-space face normal (the last writer wins where triangles share a
// voxel).
#include "voxel_bits.glsl"

layout(local_size_x_id = 0) in;

struct Triangle {
    vec4 v[3];   // world-space vertices; w of v[0..2] = the material's albedo r, g, b
};
layout(set = 0, binding = 0, std430) readonly buffer Triangles { Triangle tris[]; };
layout(set = 0, binding = 1, rgba8) uniform writeonly image3D albedo_volume;
layout(set = 0, binding = 2, rgba8_snorm) uniform writeonly image3D normal_volume;

layout(push_constant) uniform Push {
    vec4 grid_min;
    vec4 scale;
    uvec4 dims;
    uvec4 extent;
} pc;

#define VOXEL_COLUMN_BEGIN(x, y) \
    vec3 face_n = cross(t.v[1].xyz - t.v[0].xyz, t.v[2].xyz - t.v[0].xyz); \
    face_n = dot(face_n, face_n) > 0.0 ? normalize(face_n) : vec3(0.0, 1.0, 0.0);
#define VOXEL_HIT(x, y, k) \
    { \
        imageStore(albedo_volume, ivec3(x, y, k), vec4(t.v[0].w, t.v[1].w, t.v[2].w, 1.0)); \
        imageStore(normal_volume, ivec3(x, y, k), vec4(face_n, 0.0)); \
    }
#define VOXEL_COLUMN_END(x, y)
#include "voxelize_core.glsl"

void main() {
    voxelize_triangle_core();
}

#version 450
// Albedo and normal volumes, step 2 of 2 (see voxelize_attributes.comp): every voxel a
// triangle touched takes the albedo and world-space face normal of its owner (the smallest
// triangle index) and resets the owner for the next rewrite. Other voxels keep their values,
// so the atlas voxelizer's volumes (voxelize_atlas_resolve) can share the images.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

struct Triangle {
    vec4 v[3];   // world-space vertices; w of v[0..2] = the material's albedo r, g, b
};
layout(set = 0, binding = 0, std430) readonly buffer Triangles { Triangle tris[]; };
layout(set = 0, binding = 1, r32ui) uniform uimage3D owner_volume;
layout(set = 0, binding = 2, rgba8) uniform writeonly image3D albedo_volume;
layout(set = 0, binding = 3, rgba8_snorm) uniform writeonly image3D normal_volume;

const uint NO_OWNER = 0xffffffffu;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, imageSize(owner_volume)))) {
        return;
    }
    uint owner = imageLoad(owner_volume, v).x;
    if (owner == NO_OWNER) {
        return;
    }
    Triangle t = tris[owner];
    // The face normal exactly as voxelize_attributes.comp computed it before it kept owners.
    vec3 n = cross(t.v[1].xyz - t.v[0].xyz, t.v[2].xyz - t.v[0].xyz);
    n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    imageStore(albedo_volume, v, vec4(t.v[0].w, t.v[1].w, t.v[2].w, 1.0));
    imageStore(normal_volume, v, vec4(n, 0.0));
    imageStore(owner_volume, v, uvec4(NO_OWNER));
}

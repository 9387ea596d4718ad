#version 450
// Albedo and normal volumes, step 2 of 2 (see voxelize_attributes.comp): every voxel a
// triangle touched takes the albedo and world-space face normal of its owner (the smallest
// triangle index), and in the normal's w where the owner's plane cuts the voxel
// (gi_common.glsl's voxel_surface_point reads it), and resets the owner for the next rewrite. Other voxels keep their values,
// so the atlas voxelizer's volumes (voxelize_atlas_resolve) can share the images.
// With HAS_MAPS (scenes with map_Kd, src/voxel/maps.rs) an owner whose material has an albedo
// texture takes the texture's linear mean over its own part of the voxel
// (voxel_owner_maps.glsl), as the emission and material passes take theirs: the G-buffer's
// map_Kd replaces Kd, and so does the volume's.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(constant_id = 0) const bool HAS_MAPS = false;

struct Triangle {
    vec4 v[3];   // world-space vertices; w of v[0..2] = the material's albedo r, g, b
    vec4 coverage;   // read by voxelize_attributes.comp only
};
layout(set = 0, binding = 0, std430) readonly buffer Triangles { Triangle tris[]; };
layout(set = 0, binding = 1, r32ui) uniform uimage3D owner_volume;
layout(set = 0, binding = 2, rgba8) uniform writeonly image3D albedo_volume;
layout(set = 0, binding = 3, rgba8_snorm) uniform writeonly image3D normal_volume;
// Read only with HAS_MAPS (bound to the triangles otherwise): per triangle its GpuTriangleMaps
// as three vec4s, the albedo map in maps.w.
layout(set = 0, binding = 4, std430) readonly buffer AlbedoMaps { vec4 albedo_maps[]; };
#define VOXEL_MAPS_TEXELS_BINDING 5
#define VOXEL_MAPS_TABLE_BINDING 6
#include "voxel_maps.glsl"

layout(push_constant) uniform Push {
    vec4 grid_min;
    vec4 scale;
    uvec4 dims;     // res_x, res_y, D, depth axis
    uvec4 extent;   // unused here
} pc;

#include "voxel_owner_maps.glsl"

const uint NO_OWNER = 0xffffffffu;

#include "voxel_space.glsl"

// The signed distance of the owner's plane from the centre of voxel v, in voxel units along
// the plane's voxel-space normal, over sqrt(3)/2: the triangle touches the unit cube, so its
// plane passes within half the cube's diagonal of the centre and the value lies in [-1, 1]
// (an 8-bit snorm keeps it to 0.007 voxels).
float voxel_plane_offset(Triangle t, ivec3 v) {
    vec3 a = to_voxel(t.v[0].xyz);
    vec3 nv = cross(to_voxel(t.v[1].xyz) - a, to_voxel(t.v[2].xyz) - a);
    if (dot(nv, nv) <= 0.0) return 0.0;
    return clamp(dot(normalize(nv), a - (vec3(v) + 0.5)) / 0.8660254, -1.0, 1.0);
}

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
    vec3 albedo = vec3(t.v[0].w, t.v[1].w, t.v[2].w);
    if (HAS_MAPS) {
        int map = floatBitsToInt(albedo_maps[3u * owner + 2u].w);
        if (map >= 0) {
            vec4 mean_r, mean_m, mean_e, mean_a;
            owner_map_means(owner, v, albedo_maps[3u * owner], albedo_maps[3u * owner + 1u],
                            ivec4(-1, -1, -1, map), mean_r, mean_m, mean_e, mean_a);
            albedo = mean_a.rgb;
        }
    }
    imageStore(albedo_volume, v, vec4(albedo, 1.0));
    imageStore(normal_volume, v, vec4(n, voxel_plane_offset(t, v)));
    imageStore(owner_volume, v, uvec4(NO_OWNER));
}

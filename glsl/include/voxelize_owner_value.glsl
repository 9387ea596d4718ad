// A per-triangle value into a volume congruent with the bit grid, between steps 1 and 2 of the
// albedo and normal volumes (see voxelize_attributes.comp): every voxel a triangle touched takes
// the value of the same owner triangle whose albedo and normal voxelize_attributes_resolve.comp
// stores, so the volumes agree voxel by voxel. Other voxels keep their values. Included by
// voxelize_emission.comp (OWNER_VALUE_EMISSION) and voxelize_material.comp
// (OWNER_VALUE_MATERIAL), which differ in what the value means and which maps replace it.
//
// With HAS_MAPS (src/voxel/maps.rs) each triangle's row holds four vec4s: the constant value,
// then its GpuTriangleMaps (voxel_maps.glsl). An owner with a map takes the map's mean over its
// own part of the voxel (voxel_owner_maps.glsl). Emission is Ke times map_Ke; map_Pr / map_Pm
// replace the GGX roughness / metalness (first channel, clamped to [0, 1], as the G-buffer
// reads them).
#ifndef VOXELIZE_OWNER_VALUE_GLSL
#define VOXELIZE_OWNER_VALUE_GLSL

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(constant_id = 0) const bool HAS_MAPS = false;

// Per triangle: the value (HAS_MAPS: then its GpuTriangleMaps as three vec4s).
layout(set = 0, binding = 0, std430) readonly buffer Values { vec4 values[]; };
layout(set = 0, binding = 1, r32ui) uniform readonly uimage3D owner_volume;
layout(set = 0, binding = 2, rgba16f) uniform writeonly image3D value_volume;
struct Triangle {
    vec4 v[3];   // world-space vertices (w: albedo, unused here)
    vec4 coverage;   // read by voxelize_attributes.comp only
};
// Read only with HAS_MAPS (the bindings below are bound to the values otherwise).
layout(set = 0, binding = 3, std430) readonly buffer Triangles { Triangle tris[]; };
#define VOXEL_MAPS_TEXELS_BINDING 4
#define VOXEL_MAPS_TABLE_BINDING 5
#include "voxel_maps.glsl"

layout(push_constant) uniform Push {
    vec4 grid_min;
    vec4 scale;
    uvec4 dims;     // res_x, res_y, D, depth axis
    uvec4 extent;   // unused here
} pc;

const uint NO_OWNER = 0xffffffffu;

#include "voxel_owner_maps.glsl"

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, imageSize(owner_volume)))) {
        return;
    }
    uint owner = imageLoad(owner_volume, v).x;
    if (owner == NO_OWNER) {
        return;
    }
    if (!HAS_MAPS) {
        imageStore(value_volume, v, values[owner]);
        return;
    }
    vec4 value = values[4u * owner];
    vec4 uv01 = values[4u * owner + 1u];
    vec4 uv2_lod = values[4u * owner + 2u];
    // The albedo map is the resolve pass's (voxelize_attributes_resolve.comp).
    ivec4 maps = ivec4(floatBitsToInt(values[4u * owner + 3u].xyz), -1);
#ifdef OWNER_VALUE_EMISSION
    maps.xy = ivec2(-1);
#else
    maps.z = -1;
#endif
    if (all(lessThan(maps, ivec4(0)))) {
        imageStore(value_volume, v, value);
        return;
    }
    vec4 mean_r, mean_m, mean_e, mean_a;
    owner_map_means(owner, v, uv01, uv2_lod, maps, mean_r, mean_m, mean_e, mean_a);
#ifdef OWNER_VALUE_EMISSION
    value.rgb *= mean_e.rgb;
#else
    // GGX texels (r, m, 0, -1) only carry maps (MapUse::maps_of).
    if (maps.x >= 0) value.r = clamp(mean_r.r, 0.0, 1.0);
    if (maps.y >= 0) value.g = clamp(mean_m.r, 0.0, 1.0);
#endif
    imageStore(value_volume, v, value);
}

#endif

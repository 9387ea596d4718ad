// A per-triangle value into a volume congruent with the bit grid, between steps 1 and 2 of the
// albedo and normal volumes (see voxelize_attributes.comp): every voxel a triangle touched takes
// the value of the same owner triangle whose albedo and normal voxelize_attributes_resolve.comp
// stores, so the volumes agree voxel by voxel. Other voxels keep their values. Included by
// voxelize_emission.comp (OWNER_VALUE_EMISSION) and voxelize_material.comp
// (OWNER_VALUE_MATERIAL), which differ in what the value means and which maps replace it.
//
// With HAS_MAPS (src/voxel/maps.rs) each triangle's row holds four vec4s: the constant value,
// then its GpuTriangleMaps (voxel_maps.glsl). An owner with a map takes the map's mean over its
// own part of the voxel: 4 x 4 points on the voxel's face across the triangle's dominant normal
// axis, projected along that axis onto the triangle's plane (a parallel projection scales every
// area of the plane alike, so equally spaced points weigh equal areas); points outside the
// triangle or the voxel drop out. A sliver that no point hits takes the triangle's point
// nearest the voxel's centre (barycentric weights clamped). Emission is Ke times map_Ke;
// map_Pr / map_Pm replace the GGX roughness / metalness (first channel, clamped to [0, 1], as
// the G-buffer reads them).
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

// World point -> continuous voxel coordinates (VoxelGrid::world_to_voxel).
vec3 owner_to_voxel(vec3 p) {
    vec3 d = p - pc.grid_min.xyz;
    vec3 f = pc.dims.w == 0u ? d.yzx : (pc.dims.w == 1u ? d.zxy : d);
    return f * pc.scale.xyz;
}

// The owner's maps averaged over its part of voxel v (see the top): rgba of every map in
// `maps` (one per row: roughness, metallic, emission; -1 none).
void owner_map_means(uint owner, ivec3 v, vec4 uv01, vec4 uv2_lod, ivec3 maps,
                     out vec4 mean_r, out vec4 mean_m, out vec4 mean_e) {
    Triangle t = tris[owner];
    vec3 a = owner_to_voxel(t.v[0].xyz) - vec3(v);
    vec3 b = owner_to_voxel(t.v[1].xyz) - vec3(v);
    vec3 c = owner_to_voxel(t.v[2].xyz) - vec3(v);
    vec3 n = cross(b - a, c - a);
    vec3 an = abs(n);
    // The dominant axis d and the face axes (i, j).
    int d = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    int i = (d + 1) % 3;
    int j = (d + 2) % 3;
    vec2 a2 = vec2(a[i], a[j]), b2 = vec2(b[i], b[j]), c2 = vec2(c[i], c[j]);
    float area2 = (b2.x - a2.x) * (c2.y - a2.y) - (b2.y - a2.y) * (c2.x - a2.x);
    float lod = uv2_lod.z;
    mean_r = vec4(0.0);
    mean_m = vec4(0.0);
    mean_e = vec4(0.0);
    float count = 0.0;
    if (an[d] > 0.0 && area2 != 0.0) {
        float plane = dot(n, a);
        for (int s = 0; s < 16; s++) {
            vec2 q = (vec2(s % 4, s / 4) + 0.5) * 0.25;
            float qd = (plane - n[i] * q.x - n[j] * q.y) / n[d];
            if (qd < 0.0 || qd > 1.0) continue;
            // Barycentric weights in the face's projection (exact for points of the plane).
            float w1 = ((q.x - a2.x) * (c2.y - a2.y) - (q.y - a2.y) * (c2.x - a2.x)) / area2;
            float w2 = ((b2.x - a2.x) * (q.y - a2.y) - (b2.y - a2.y) * (q.x - a2.x)) / area2;
            vec3 w = vec3(1.0 - w1 - w2, w1, w2);
            if (any(lessThan(w, vec3(0.0)))) continue;
            vec2 uv = voxel_map_uv(uv01, uv2_lod, w);
            if (maps.x >= 0) mean_r += sample_voxel_map(maps.x, uv, lod);
            if (maps.y >= 0) mean_m += sample_voxel_map(maps.y, uv, lod);
            if (maps.z >= 0) mean_e += sample_voxel_map(maps.z, uv, lod);
            count += 1.0;
        }
    }
    if (count > 0.0) {
        mean_r /= count;
        mean_m /= count;
        mean_e /= count;
        return;
    }
    // A sliver: the voxel centre's barycentric weights in the face's projection, clamped.
    vec2 q = vec2(0.5);
    vec3 w = vec3(1.0, 0.0, 0.0);
    if (area2 != 0.0) {
        float w1 = ((q.x - a2.x) * (c2.y - a2.y) - (q.y - a2.y) * (c2.x - a2.x)) / area2;
        float w2 = ((b2.x - a2.x) * (q.y - a2.y) - (b2.y - a2.y) * (q.x - a2.x)) / area2;
        w = max(vec3(1.0 - w1 - w2, w1, w2), vec3(0.0));
        w /= max(w.x + w.y + w.z, 1e-30);
    }
    vec2 uv = voxel_map_uv(uv01, uv2_lod, w);
    if (maps.x >= 0) mean_r = sample_voxel_map(maps.x, uv, lod);
    if (maps.y >= 0) mean_m = sample_voxel_map(maps.y, uv, lod);
    if (maps.z >= 0) mean_e = sample_voxel_map(maps.z, uv, lod);
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
    if (!HAS_MAPS) {
        imageStore(value_volume, v, values[owner]);
        return;
    }
    vec4 value = values[4u * owner];
    vec4 uv01 = values[4u * owner + 1u];
    vec4 uv2_lod = values[4u * owner + 2u];
    ivec3 maps = floatBitsToInt(values[4u * owner + 3u].xyz);
#ifdef OWNER_VALUE_EMISSION
    maps.xy = ivec2(-1);
#else
    maps.z = -1;
#endif
    if (all(lessThan(maps, ivec3(0)))) {
        imageStore(value_volume, v, value);
        return;
    }
    vec4 mean_r, mean_m, mean_e;
    owner_map_means(owner, v, uv01, uv2_lod, maps, mean_r, mean_m, mean_e);
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

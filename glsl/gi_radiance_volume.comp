#version 450
// Direct-radiance voxel volume (Thiedemann 2010, §6.3.2, the alternative to reflective light maps for
// diffuse senders): for every occupied voxel, the radiance its surface reflects from every
// light, rho/pi * E with shadow-map visibility, on the side the light reaches (stored in a as
// +1: along the normal volume's normal, -1: against it). In scenes with emitters the emitted
// radiance (emission volume, leaving the side the normal points to) adds to that side's.
#include "frame.glsl"
#include "gi_common.glsl"

layout(constant_id = 0) const bool HAS_EMISSION = false;

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform usampler2DArray voxels;
layout(set = 0, binding = 2) uniform sampler3D albedo_volume;
layout(set = 0, binding = 3) uniform sampler3D normal_volume;
layout(set = 0, binding = 4) uniform sampler2DArray shadow_maps;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image3D radiance_volume;
layout(set = 0, binding = 6) uniform sampler3D emission_volume;  // albedo when !HAS_EMISSION

#include "shadow.glsl"

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, gi.dims))) return;
    uvec4 column = texelFetch(voxels, ivec3(v.xy, v.z / 128), 0);
    uint bit = uint(v.z) % 128u;
    if (((column[bit / 32u] >> (bit % 32u)) & 1u) == 0u) {
        imageStore(radiance_volume, v, vec4(0.0));
        return;
    }
    mat4 to_world = inverse(gi.world_to_voxel);
    vec3 p = (to_world * vec4(vec3(v) + 0.5, 1.0)).xyz;
    vec3 n = texelFetch(normal_volume, v, 0).xyz;
    n = dot(n, n) > 0.25 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    vec3 a = texelFetch(albedo_volume, v, 0).rgb;
    vec3 lit[2] = vec3[2](vec3(0.0), vec3(0.0));
    for (int side = 0; side < 2; ++side) {
        vec3 ns = side == 0 ? n : -n;
        // Shadow lookups from a voxel diagonal off the voxel center on that side, so the
        // surface inside the voxel does not shadow itself.
        vec3 ps = p + ns * gi.voxel_diagonal_m;
        for (uint i = 0u; i < frame.counts.x; ++i) {
            GpuLight l = frame.lights[i];
            vec3 wi;
            vec3 e;
            if (l.info.x == LIGHT_DIRECTIONAL) {
                wi = -l.direction.xyz;
                e = l.intensity.rgb * max(dot(ns, wi), 0.0);
            } else {
                vec3 d = l.position.xyz - p;
                float d2 = max(dot(d, d), 1e-30);
                wi = d * inversesqrt(d2);
                float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
                e = l.intensity.rgb * (falloff * max(dot(ns, wi), 0.0) / d2);
            }
            if (all(equal(e, vec3(0.0)))) continue;
            lit[side] += a / PI * e * shadow_visibility(shadow_maps, l, ps, ns, max(dot(ns, wi), 0.0));
        }
    }
    if (HAS_EMISSION) lit[0] += texelFetch(emission_volume, v, 0).rgb;
    bool front = dot(lit[0], vec3(1.0)) >= dot(lit[1], vec3(1.0));
    imageStore(radiance_volume, v, vec4(front ? lit[0] : lit[1], front ? 1.0 : -1.0));
}

#version 450
// Further VPL bounces (Thiedemann 2010, §7.2): from every VPL of bounce b-1 one ray,
// cosine-distributed around its normal (Halton bases 5, 7, shifted per bounce), through the
// binary voxel hierarchy (the Lambert part of a Phong sender's flux); at the hit the albedo and normal come from the attribute volumes
// congruent with the bits, and the new VPL reflects Phi_b = Phi_(b-1) * rho_hit. Cosine
// sampling makes this unbiased for a Lambert sender: the flux leaving the sender is Phi_(b-1),
// and the ray picks where it arrives with probability proportional to that flux. A ray that
// leaves the grid carries its flux out of the scene: the new VPL is invalid (zero flux).
#define GI_OWN_PUSH
#define VPL_GENERATE_PUSH
#include "gi_common.glsl"
#include "vpl.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform usampler2DArray voxels;
layout(set = 0, binding = 1, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 2) uniform sampler3D albedo_volume;
layout(set = 0, binding = 3) uniform sampler3D normal_volume;
layout(set = 0, binding = 4, std430) buffer Vpls { GpuVpl vpls[]; };

uvec4 vx_column(uint level, int x, int y, uint layer) {
    return texelFetch(voxels, ivec3(x, y, int(layer)), int(level));
}
uvec4 vx_ray_mask(uint a, uint b) { return ray_masks[b * 128u + a]; }
bool vx_voxel(int x, int y, int k) {
    uvec4 c = vx_column(0u, x, y, uint(k) / 128u);
    uint bit = uint(k) % 128u;
    return ((c[bit / 32u] >> (bit % 32u)) & 1u) != 0u;
}

#include "voxel_traverse.glsl"

void main() {
    uint lights = pc.counts.y;
    uint k = pc.counts.z;
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.counts.x * lights * k) return;
    uint set_ = i / (lights * k);
    uint light = (i / k) % lights;
    uint kk = i % k;
    uint b = pc.trace.z;
    GpuVpl src = vpls[vpl_index(set_, b - 1u, light, kk)];
    uint dst = vpl_index(set_, b, light, kk);
    GpuVpl none = GpuVpl(vec4(0.0), vec4(0.0, 0.0, 1.0, 0.0), vec4(0.0, 0.0, 0.0, float(b)), vec4(0.0), vec4(0.0));
    if (src.position.w == 0.0 || all(equal(src.flux.rgb, vec3(0.0)))) {
        vpls[dst] = none;
        return;
    }
    uint j = set_ * k + kk + 1u;
    // A golden-ratio shift per bounce decorrelates the bounces' directions.
    vec2 u = fract(vec2(halton(j, 5u), halton(j, 7u)) + float(b - 1u) * vec2(0.618034, 0.381966));
    vec3 n = src.normal.xyz;
    vec3 d = cosine_direction(n, u);
    // Self-intersection offset along the normal (§5.3.1).
    vec3 o = src.position.xyz + n * (pc.params.x * pc.params.y);
    vec3 ov = (pc.world_to_voxel * vec4(o, 1.0)).xyz;
    VxHit h = voxel_first_hit(pc.dims.xyz, uint(pc.dims.w), ov, mat3(pc.world_to_voxel) * d, pc.params.z, pc.trace.x, pc.trace.y);
    if (!h.hit) {
        vpls[dst] = none;
        return;
    }
    ivec3 v = ivec3(h.voxel);
    vec3 albedo = texelFetch(albedo_volume, v, 0).rgb;
    vec3 hn = texelFetch(normal_volume, v, 0).xyz;
    hn = dot(hn, hn) > 0.25 ? normalize(hn) : -d;
    if (dot(hn, d) > 0.0) hn = -hn;  // the side the ray arrives at
    // Diffuse senders only: the volumes hold the albedo, not the specular reflectance.
    vpls[dst] = GpuVpl(vec4(o + d * h.t, 1.0), vec4(hn, 0.0), vec4(src.flux.rgb * albedo, float(b)), vec4(0.0), vec4(0.0));
}

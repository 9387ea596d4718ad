#version 450
// Further VPL bounces (Thiedemann 2010, §7.2): from every VPL of bounce b-1 one ray (Halton
// bases 5, 7, shifted per bounce) through the binary voxel hierarchy; at the hit the albedo and
// normal come from the attribute volumes congruent with the bits, and the new VPL reflects
// Phi_b = Phi_(b-1) * rho_hit. A Lambert sender's ray is cosine-distributed around its
// normal: the flux leaving it is Phi_(b-1), and the ray picks where it arrives with
// probability proportional to that flux, so the estimator is unbiased.
//
// A glossy sender (vpl.glsl: intensity f(wi, w) Phi_in cos theta) leaves the flux
// Phi_out = integral f(wi, w) Phi_in cos theta dw. The ray samples one of its two lobes as the
// path tracer does (material_lobe.glsl's sample_lobe, with wi in the place of wo: the BRDFs are
// reciprocal), the specular one with probability P_s (1 for a black diffuse part, as metals
// have, else 1/2), and carries that lobe's part divided by its probability: the specular lobe
// Phi_in f cos / pdf / P_s (GGX: Phi_in F(wi.h) G1(w) for visible normals, Heitz 2018; Phong:
// Phi_in rho_s (n+2)/(n+1) cos), the diffuse lobe (cosine-distributed) Phi_VPL / (1 - P_s),
// times (1 - F_d(n.w)) for GGX. Each lobe's integral is estimated by its own samples, so the
// carried flux is unbiased. With Phong or GGX materials (HAS_LOBES) the hit's material comes
// from the material volume and a glossy hit becomes a glossy VPL (vpl.glsl's hit_vpl);
// without, hits are Lambert. A ray that leaves the grid carries its flux out of the scene: the
// new VPL is invalid (zero flux).
#define GI_OWN_PUSH
#define VPL_GENERATE_PUSH
#define VPL_HIT
#include "gi_common.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"
#include "vpl.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform usampler2DArray voxels;
layout(set = 0, binding = 1, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 2) uniform sampler3D albedo_volume;
layout(set = 0, binding = 3) uniform sampler3D normal_volume;
layout(set = 0, binding = 4, std430) buffer Vpls { GpuVpl vpls[]; };
// The material volume (src/voxel/attributes.rs, `material_texel`); read only when HAS_LOBES.
layout(set = 0, binding = 5) uniform sampler3D material_volume;
layout(constant_id = 3) const bool HAS_LOBES = false;

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
    GpuVpl none = GpuVpl(vec4(0.0), vec4(0.0, 0.0, 1.0, 0.0), vec4(0.0, 0.0, 0.0, float(b)), vec4(0.0), vec4(0.0), vec4(0.0));
    bool glossy = HAS_LOBES && src.specular.w > 0.5;
    bool lit = any(greaterThan(src.flux.rgb, vec3(0.0))) || (glossy && any(greaterThan(src.incident.rgb, vec3(0.0))));
    if (src.position.w == 0.0 || !lit) {
        vpls[dst] = none;
        return;
    }
    uint j = halton_point(set_, kk);
    // A golden-ratio shift per bounce decorrelates the bounces' directions.
    vec2 u = fract(vec2(halton(j, 5u), halton(j, 7u)) + float(b - 1u) * vec2(0.618034, 0.381966));
    vec3 n = src.normal.xyz;
    vec3 d;
    vec3 phi;
    if (glossy) {
        // The sender's lobe (above): a black diffuse part always takes the specular lobe.
        Lobe m = Lobe(uint(src.specular.w + 0.5), src.flux.rgb, src.specular.rgb, src.lobe.w);
        float p_s = lobe_specular_probability(m);
        vec3 wi = src.lobe.xyz;
        bool specular = fract(halton(j, 17u) + float(b - 1u) * 0.618034) < p_s;
        vec3 weight;
        d = sample_lobe(m, n, wi, specular, u, weight);
        if (specular) {
            phi = src.incident.rgb * weight / p_s;
        } else {
            // sample_lobe's GGX diffuse weight holds (1 - F_d(n.wi)) too, which Phi_VPL has.
            float fd = m.kind == LOBE_GGX ? ggx_diffuse_weight(dot(n, d)) : 1.0;
            phi = src.flux.rgb * (fd / (1.0 - p_s));
        }
        if (dot(d, n) <= 0.0 || all(equal(phi, vec3(0.0)))) {
            vpls[dst] = none;
            return;
        }
    } else {
        d = cosine_direction(n, u);
        phi = src.flux.rgb;
    }
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
    Lobe hit = HAS_LOBES ? voxel_lobe(albedo, texelFetch(material_volume, v, 0)) : lambert_lobe(albedo);
    vpls[dst] = hit_vpl(o + d * h.t, hn, d, phi, hit, float(b));
}

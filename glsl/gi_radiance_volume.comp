#version 450
// Direct-radiance voxel volume (Thiedemann 2010, §6.3.2, the alternative to reflective light maps for
// diffuse senders): for every occupied voxel, the radiance its surface reflects from every
// light, rho/pi * E with shadow-map visibility, on the side the light reaches (stored in a as
// +1: along the normal volume's normal, -1: against it). In scenes with emitters the emitted
// radiance (emission volume, leaving the side the normal points to) adds to that side's.
// With Phong or GGX materials (HAS_LOBES) the stored part is a glossy voxel's diffuse part, as
// the light maps store it: Phong rho_d / pi * E (rho_d the albedo volume's value), GGX
// (1 - m) b / pi * (1 - F_d(n.wi)) * E (b the albedo volume's base color, m from the material
// volume); gi_hemisphere_volume.comp adds the specular lobe toward each ray at its hit, with
// the voxel's visibility of its lights, which a glossy voxel keeps in a (below).
//
// With HAS_EMITTERS (emissive triangles and `gi.emitter_sampling`) each voxel side also gets
// the emitters' light by next-event estimation, as the path tracer's vertices do
// (emitters.glsl's emitter_sample_from: a triangle by power, a point on it, visibility by the
// voxel segment test): EMITTER_SAMPLES light samples of the diffuse part, the whole estimate
//   rho/pi * 1/K sum L cos_i cos_l / (d^2 p_A),
// so a ray of gi_hemisphere_volume that hits a wall lit by a lamp brings the lamp's light
// reflected there, the second bounce the emission volume alone cannot give (it holds the
// lamp's own radiance, the first).
#include "frame.glsl"
#include "gi_common.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"

layout(constant_id = 0) const bool HAS_EMISSION = false;
// Some material is Phong or GGX: binding 7 is the material volume.
layout(constant_id = 1) const bool HAS_LOBES = false;
// Sample the emitter list (binding 14) and trace the voxels (binding 8 the ray-mask table).
layout(constant_id = 2) const bool HAS_EMITTERS = false;
// Light samples per voxel side: the volume is computed once per accumulation (first_frame)
// and every hemisphere ray that hits the voxel reads it, so its noise is averaged by the
// gather's many rays over many voxels; 16 keeps the pass near its cost without emitters.
const uint EMITTER_SAMPLES = 16u;

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform usampler2DArray voxels;
layout(set = 0, binding = 2) uniform sampler3D albedo_volume;
layout(set = 0, binding = 3) uniform sampler3D normal_volume;
layout(set = 0, binding = 4) uniform sampler2DArray shadow_maps;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image3D radiance_volume;
layout(set = 0, binding = 6) uniform sampler3D emission_volume;  // albedo when !HAS_EMISSION
layout(set = 0, binding = 7) uniform sampler3D material_volume;  // albedo when !HAS_LOBES

layout(set = 0, binding = 8, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };

#include "shadow.glsl"
#include "voxel_light.glsl"

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
#define EMITTERS_BINDING 14
#include "emitters.glsl"

// The emitters' light the side of normal ns at voxel centre p reflects (rho/pi E, E by
// EMITTER_SAMPLES light samples, Hammersley rotated per voxel and side). The rays leave k1
// voxel diagonals off the surface along its normal, as the GI rays do; the light's geometry
// is the voxel centre's.
vec3 emitters_lit(ivec3 v, vec3 p, vec3 ns, vec3 albedo, uint side) {
    vec3 o = p + ns * (gi.normal_offset_voxels * gi.voxel_diagonal_m);
    vec2 rot = pixel_rotation(uvec2(v.x + v.z * 4099, v.y), side * 0x9e37u + 0x51u);
    vec3 e = vec3(0.0);
    for (uint s = 0u; s < EMITTER_SAMPLES; ++s) {
        vec2 u = fract(vec2((float(s) + 0.5) / float(EMITTER_SAMPLES), radical_inverse(s)) + rot);
        e += emitter_sample_from(p, o, ns, ns, lambert_lobe(albedo), 3u, 0.0, u);
    }
    return e / float(EMITTER_SAMPLES);
}

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
    bool ggx = false;
    bool glossy = false;
    if (HAS_LOBES) {
        Lobe m = voxel_lobe(a, texelFetch(material_volume, v, 0));
        ggx = m.kind == LOBE_GGX;
        glossy = m.kind != LOBE_LAMBERT;
        a = m.diffuse;
    }
    vec3 lit[2] = vec3[2](vec3(0.0), vec3(0.0));
    // With lobes: the sums over lights and sides of |E| V and |E| (|E| the sum of E's
    // channels), whose ratio the lookup's specular lobe takes as its visibility.
    float e_visible = 0.0;
    float e_total = 0.0;
    for (int side = 0; side < 2; ++side) {
        vec3 ns = side == 0 ? n : -n;
        for (uint i = 0u; i < frame.counts.x; ++i) {
            GpuLight l = frame.lights[i];
            vec3 wi;
            vec3 e = voxel_light_e(l, p, ns, wi);
            if (all(equal(e, vec3(0.0)))) continue;
            vec3 d = a;
            if (HAS_LOBES) {
                if (ggx) d *= ggx_diffuse_weight(dot(ns, wi));
                float visibility = voxel_light_visibility(shadow_maps, l, p, ns, wi);
                lit[side] += d / PI * e * visibility;
                e_visible += dot(e, vec3(1.0)) * visibility;
                e_total += dot(e, vec3(1.0));
                continue;
            }
            lit[side] += d / PI * e * voxel_light_visibility(shadow_maps, l, p, ns, wi);
        }
        // The emitters' light, with the diffuse albedo (a glossy voxel's diffuse part; GGX's
        // (1 - F_d) factor, which depends on the light's direction, is left out here).
        if (HAS_EMITTERS) lit[side] += emitters_lit(v, p, ns, a, uint(side));
    }
    // The half-float emission volume holds pre-exposed radiance (frame.glsl).
    if (HAS_EMISSION) lit[0] += texelFetch(emission_volume, v, 0).rgb * frame.radiance_scale.y;
    bool front = dot(lit[0], vec3(1.0)) >= dot(lit[1], vec3(1.0));
    float side_flag = front ? 1.0 : -1.0;
    // A glossy voxel keeps its lights' irradiance-weighted visibility V = sum |E| V_l / sum |E|
    // as |a| = 1 + V for gi_hemisphere_volume's specular lobe: exactly the light's visibility
    // with one light (E is 0 on its other side), the mean where several lights reach the voxel.
    if (HAS_LOBES && glossy) side_flag *= 1.0 + (e_total > 0.0 ? e_visible / e_total : 0.0);
    imageStore(radiance_volume, v, vec4(front ? lit[0] : lit[1], side_flag));
}

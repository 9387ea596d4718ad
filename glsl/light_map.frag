#version 450
// Reflective light maps: what the light sees is directly lit by it, so each texel stores the
// radiance leaving that surface (Lambert: rho/pi * E, E = I cos / d^2 with Mitsuba's spot
// falloff; the diffuse part), its world position and material and its normal, for lookups at
// voxel ray hits (Thiedemann 2010, §6.3.3). A GGX sender's diffuse part is
// (1 - m) b / pi (1 - F_d(n.wi)) E (brdf.glsl's brdf_ggx without the factor (1 - F_d(n.wo))
// toward the receiver, which the map cannot know: 0.96 along the normal, 0 at grazing); its
// specular lobe sends nothing here, so a metal (m = 1) sends no light-map light.
#include "frame.glsl"
#include "dissolve.glsl"

// Some material has MTL d < 1: its texels are covered as in the shadow maps (dissolve.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;
layout(constant_id = 1) const bool HAS_GGX = false;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// GGX parameters per material (gbuffer.frag's table; read only when HAS_GGX).
struct GpuMaterialPbr { vec4 ggx; vec4 emission; uvec4 maps; };
layout(set = 0, binding = 2, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
} pc;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec3 in_world;

layout(location = 0) out vec4 out_radiance;
layout(location = 1) out vec4 out_position;
layout(location = 2) out vec4 out_normal;

#define PI 3.14159265358979323846

void main() {
    // Before any discard: the threshold takes derivatives.
    float coverage_threshold = HAS_DISSOLVE ? dissolve_threshold(in_world) : 0.0;
    // The shadow views index their light through the light table.
    GpuLight l;
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight c = frame.lights[i];
        if (pc.view >= c.info.y && pc.view < c.info.y + c.info.z) l = c;
    }
    vec3 n = normalize(in_normal);
    vec3 e;
    float cos_i;
    if (l.info.x == LIGHT_DIRECTIONAL) {
        if (dot(n, -l.direction.xyz) < 0.0) n = -n;
        cos_i = max(dot(n, -l.direction.xyz), 0.0);
        e = l.intensity.rgb * cos_i;
    } else {
        vec3 d = l.position.xyz - in_world;
        float d2 = max(dot(d, d), 1e-30);
        vec3 wi = d * inversesqrt(d2);
        // Two-sided: the side the light sees.
        if (dot(n, wi) < 0.0) n = -n;
        float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
        cos_i = max(dot(n, wi), 0.0);
        e = l.intensity.rgb * (falloff * cos_i / d2);
    }
    GpuMaterial m = materials[pc.material];
    if (HAS_DISSOLVE && m.albedo.a < coverage_threshold) discard;
    vec3 diffuse = m.albedo.rgb;
    if (HAS_GGX && pbr[pc.material].ggx.z != 0.0) {
        // Schlick with F0 = 0.04 (brdf.glsl's fresnel_schlick), inlined.
        float f_d = 0.04 + 0.96 * pow(1.0 - clamp(cos_i, 0.0, 1.0), 5.0);
        diffuse *= (1.0 - pbr[pc.material].ggx.y) * (1.0 - f_d);
    }
    out_radiance = vec4(diffuse / PI * e, 1.0);
    // w: material index + 1 (0 marks texels the light sees nothing in), so lookups can
    // evaluate a glossy sender's lobe toward the ray (§6.4.3).
    out_position = vec4(in_world, float(pc.material + 1u));
    out_normal = vec4(n, 0.0);
}

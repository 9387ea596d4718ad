#version 450
// Reflective light maps: what the light sees is directly lit by it, so each texel stores the
// radiance leaving that surface (Lambert: rho/pi * E, E = I cos / d^2 with Mitsuba's spot
// falloff; the diffuse part), its world position and material and its normal, for lookups at
// voxel ray hits (Thiedemann 2010, §6.3.3).
#include "frame.glsl"
#include "dissolve.glsl"

// Some material has MTL d < 1: its texels are covered as in the shadow maps (dissolve.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };

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
    if (l.info.x == LIGHT_DIRECTIONAL) {
        if (dot(n, -l.direction.xyz) < 0.0) n = -n;
        e = l.intensity.rgb * max(dot(n, -l.direction.xyz), 0.0);
    } else {
        vec3 d = l.position.xyz - in_world;
        float d2 = max(dot(d, d), 1e-30);
        vec3 wi = d * inversesqrt(d2);
        // Two-sided: the side the light sees.
        if (dot(n, wi) < 0.0) n = -n;
        float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
        e = l.intensity.rgb * (falloff * max(dot(n, wi), 0.0) / d2);
    }
    GpuMaterial m = materials[pc.material];
    if (HAS_DISSOLVE && m.albedo.a < coverage_threshold) discard;
    out_radiance = vec4(m.albedo.rgb / PI * e, 1.0);
    // w: material index + 1 (0 marks texels the light sees nothing in), so lookups can
    // evaluate a glossy sender's lobe toward the ray (§6.4.3).
    out_position = vec4(in_world, float(pc.material + 1u));
    out_normal = vec4(n, 0.0);
}

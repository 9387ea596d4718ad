#version 450
// Shadow maps store depth only; materials with MTL d < 1 cover a fraction d of the texels
// (dissolve.glsl), so their shadows are partial.
layout(constant_id = 0) const bool HAS_DISSOLVE = false;

#include "dissolve.glsl"

struct GpuMaterial {
    vec4 albedo;  // a: opacity (gbuffer.frag has the whole layout)
    vec4 specular;
    uvec4 flags;
};
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

// World position (shadow_depth.geom, non-paraboloid views).
layout(location = 5) in vec3 in_world;

void main() {
    if (HAS_DISSOLVE && materials[pc.material].albedo.a < dissolve_threshold(in_world)) discard;
}

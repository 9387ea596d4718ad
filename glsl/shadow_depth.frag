#version 450
// Shadow maps store depth only; materials with MTL d < 1 cover a fraction d of the texels
// (dissolve.glsl), so their shadows are partial; alpha maps cut or thin them per texel
// (alpha_map.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;
layout(constant_id = 1) const bool HAS_ALPHA_MAP = false;

#include "dissolve.glsl"
#include "alpha_map.glsl"

struct GpuMaterial {
    vec4 albedo;  // a: opacity (gbuffer.frag has the whole layout)
    vec4 specular;
    uvec4 flags;  // w: the alpha map's mode (alpha_map.glsl)
};
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// The draw's texture, whose alpha is the alpha map (the placeholder where it has none); read
// only with HAS_ALPHA_MAP.
layout(set = 0, binding = 2) uniform sampler2D alpha_texture;

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

// World position (shadow_depth.geom, non-paraboloid views).
layout(location = 5) in vec3 in_world;
layout(location = 6) in vec2 in_tex_uv;

void main() {
    GpuMaterial m = materials[pc.material];
    float opacity = m.albedo.a;
    // Image rows start at the top (OBJ's v points up), as in the G-buffer.
    if (HAS_ALPHA_MAP) {
        float a = texture(alpha_texture, vec2(in_tex_uv.x, 1.0 - in_tex_uv.y)).a;
        opacity = alpha_map_opacity(m.flags.w, opacity, a);
    }
    float threshold = HAS_DISSOLVE ? dissolve_threshold(in_world) : 0.0;
    if ((HAS_DISSOLVE || HAS_ALPHA_MAP) && opacity < alpha_map_keep_threshold(HAS_DISSOLVE, threshold)) discard;
}

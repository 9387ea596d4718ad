#version 450
// Shadow maps of a frame with paraboloid views (paraboloid.glsl; shadow_depth.geom covers a box
// around each triangle's curved image). A texel keeps a triangle exactly when the ray through
// its center hits the triangle, and stores the exact distance along that ray. Both interpolated
// depth (linear between the mapped vertices, while the map is not) and rasterized coverage
// (chords instead of arcs) are wrong inside large triangles (Brabec et al. 2002 and
// Dachsbacher 2014, "Echtzeit-Schattenverfahren Teil 3", ask to tessellate finely instead). Other
// views keep their rasterized depth. Paraboloid inverse (stereographic):
// d = (2x, 2y, 1 - x^2 - y^2) / (1 + x^2 + y^2).
// Materials with MTL d < 1 cover a fraction d of the texels (dissolve.glsl).
// Alpha maps cut or thin them per texel (alpha_map.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;
layout(constant_id = 1) const bool HAS_ALPHA_MAP = false;

#include "dissolve.glsl"
#include "alpha_map.glsl"
#include "paraboloid.glsl"

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

layout(location = 0) in vec2 in_uv;
layout(location = 1) flat in vec4 in_v0;  // w 1: a paraboloid view
layout(location = 2) flat in vec3 in_v1;
layout(location = 3) flat in vec3 in_v2;
layout(location = 4) flat in vec2 in_range;  // near, far
layout(location = 5) in vec3 in_world;        // the other projections
// Texture coordinates: interpolated (other projections), or vertex 2's with vertices 0 and 1
// in in_t01 (paraboloid views).
layout(location = 6) in vec2 in_tex_uv;
layout(location = 7) flat in vec4 in_t01;

// The material's opacity at texture coordinates uv (OBJ's v up), after its alpha map.
float opacity_at(GpuMaterial m, vec2 uv) {
    if (!HAS_ALPHA_MAP) return m.albedo.a;
    float a = texture(alpha_texture, vec2(uv.x, 1.0 - uv.y)).a;
    return alpha_map_opacity(m.flags.w, m.albedo.a, a);
}

void main() {
    GpuMaterial m = materials[pc.material];
    gl_FragDepth = gl_FragCoord.z;
    if (in_v0.w == 0.0) {
        float opacity = opacity_at(m, in_tex_uv);
        float threshold = HAS_DISSOLVE ? dissolve_threshold(in_world) : 0.0;
        if ((HAS_DISSOLVE || HAS_ALPHA_MAP) && opacity < alpha_map_keep_threshold(HAS_DISSOLVE, threshold)) discard;
        return;
    }
    vec3 dir, bary;
    float dist;
    bool hit = paraboloid_ray(in_uv, in_v0.xyz, in_v1, in_v2, dir, dist, bary);
    // Dissolve and the alpha map's level take derivatives of the hit point: before any discard
    // (the hemisphere frame is rigid, as good as world space for a pattern that sticks to the
    // surface).
    float coverage_threshold = HAS_DISSOLVE ? dissolve_threshold(dir * dist) : 0.0;
    float opacity = opacity_at(m, bary.x * in_t01.xy + bary.y * in_t01.zw + bary.z * in_tex_uv);
    if (!hit) discard;
    float keep = alpha_map_keep_threshold(HAS_DISSOLVE, coverage_threshold);
    if ((HAS_DISSOLVE || HAS_ALPHA_MAP) && opacity < keep) discard;
    gl_FragDepth = clamp((dist - in_range.x) / (in_range.y - in_range.x), 0.0, 1.0);
}

#version 450
// Shadow aliasing as a debug view (Dachsbacher 2014, part 3, A.3): the predicted size on
// screen, in pixels, of the shadow-map texel that shades each pixel,
//     d_i = d_s (r_s / r_i) (cos a_i / cos a_s),
// with d_s r_s the texel's world size across the light's ray at p (meters: the orthographic
// and cascade maps' texel, a perspective map's texel per meter times the distance, the
// paraboloid's texel at p), r_i / pixel_scale the world size of a pixel at p's view depth r_i
// (ortho height / height under orthographic projection),
// a_s the angle between the normal and the light, a_i between the normal and the view ray
// (a texel stretches by 1 / cos a_s over the surface and shrinks by cos a_i seen from the
// camera). Above 1 pixel the map is too coarse there (blocky edges), far below it wastes
// resolution. Per pixel the largest d_i of the lights that reach it (the cascade that shades
// it for a directional light). `value` holds (d_i px, texel m, view index), `color` a ramp of
// log2 d_i: blue <= 1/4 px, green 1 px, red >= 4 px; grey where no light reaches. With
// `projective` 0 (`--debug shadow-texels-perspective`) d_i leaves out cos a_i / cos a_s: the
// perspective aliasing a finer map removes, not the projective one no resolution fixes.
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#include "shadow.glsl"
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D value;
layout(set = 0, binding = 4, rgba8) uniform writeonly image2D color;

layout(push_constant) uniform Push {
    float pixel_scale;  // height / (2 tan(fov_y / 2)): pixels per meter at 1 m view depth
    uint projective;    // 1: with cos a_i / cos a_s; 0: the perspective part only
} pc;

// World size (m) across the light's ray at p of a texel of perspective, orthographic or
// paraboloid view v.
float texel_size_m(uint v, vec3 p) {
    GpuShadowView sv = frame.shadow_views[v];
    if (sv.params.y > 1.5) return paraboloid_texel_m(sv, p);
    if (sv.params.y > 0.5) return sv.params.x;
    return sv.params.x * max((sv.view_proj * vec4(p, 1.0)).w, 0.0);
}

vec3 ramp(float d_px) {
    float t = clamp((log2(max(d_px, 1e-30)) + 2.0) / 4.0, 0.0, 1.0);
    return t < 0.5 ? mix(vec3(0.0, 0.0, 1.0), vec3(0.0, 1.0, 0.0), 2.0 * t)
                   : mix(vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), 2.0 * t - 1.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(value);
    if (any(greaterThanEqual(px, size))) return;
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(value, px, vec4(0.0));
        imageStore(color, px, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec3 n = normalize(texelFetch(gb_normal, px, 0).xyz);
    float cos_i = abs(dot(n, toward_camera(frame.camera_position, frame.camera_forward, p)));
    // Pixels per meter at p: pixel_scale / view depth, or height / ortho height at any depth.
    bool ortho = frame_orthographic(frame.camera_forward);
    float pixel_scale = ortho ? float(size.y) / frame.camera_forward.w : pc.pixel_scale;
    float view_depth = ortho ? 1.0 : max((frame.view_proj * vec4(p, 1.0)).w, 1e-30);
    float worst = -1.0, worst_texel = 0.0, worst_view = 0.0;
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight l = frame.lights[i];
        if (l.info.z == 0u) continue;
        vec3 wi = l.info.x == LIGHT_DIRECTIONAL ? -l.direction.xyz : normalize(l.position.xyz - p);
        float cos_s = dot(n, wi);
        if (cos_s <= 0.0) continue;
        uint v = direct_shadow_view(l, p);
        float texel_m = texel_size_m(v, p);
        float projective = pc.projective != 0u ? cos_i / max(cos_s, 1e-3) : 1.0;
        float d_px = texel_m * pixel_scale * projective / view_depth;
        if (d_px > worst) {
            worst = d_px;
            worst_texel = texel_m;
            worst_view = float(v);
        }
    }
    if (worst < 0.0) {
        imageStore(value, px, vec4(0.0, 0.0, -1.0, 1.0));
        imageStore(color, px, vec4(0.25, 0.25, 0.25, 1.0));
        return;
    }
    imageStore(value, px, vec4(worst, worst_texel, worst_view, 1.0));
    imageStore(color, px, vec4(ramp(worst), 1.0));
}

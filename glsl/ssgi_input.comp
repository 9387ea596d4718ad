#version 450
// Level 0 of the screen-space GI pyramids (Oetke 2017 §5.1): per pixel the world position
// with its view depth (0: sky), the world normal, and the lit colour the gather reads: the
// direct light (with emission) plus, with FEEDBACK, the previous frame's indirect light at
// this surface point, reprojected with the previous camera and weighted by how well the
// depths agree (Oetke 2017 §2.3 and §7.5: feeding the result back gives unlimited bounces;
// the reprojected irradiance is clamped to feedback_max_w_m2 so the loop cannot explode).
#include "frame.glsl"
#include "ssgi.glsl"

layout(constant_id = 0) const bool FEEDBACK = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_depth;
layout(set = 0, binding = 2) uniform sampler2D gb_normal;
layout(set = 0, binding = 3) uniform sampler2D gb_albedo;
layout(set = 0, binding = 4) uniform sampler2D direct;
// Last frame's indirect irradiance (rgb) and each pixel's clip w (its view depth) then.
layout(set = 0, binding = 5) uniform sampler2D history;
layout(set = 0, binding = 6, std430) readonly buffer PrevCamera { mat4 prev_view_proj; };
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D out_pos;
layout(set = 0, binding = 8, rgba16f) uniform writeonly image2D out_nrm;
layout(set = 0, binding = 9, rgba32f) uniform writeonly image2D out_color;
// The reprojected history (rgb) and its weight (a), for ssgi_upsample's temporal blend.
layout(set = 0, binding = 10, rgba32f) uniform writeonly image2D out_reprojected;

layout(push_constant) uniform Push {
    float feedback_max_w_m2;   // clamp of the fed-back irradiance
} pc;

// The previous frame's irradiance at world point p (rgb, clamped) and its weight (a): the
// depth agreement (1 within 1%, 0 beyond 5%), zero outside the previous frame.
vec4 reprojected_irradiance(vec3 p) {
    ivec2 texel;
    float w;
    if (!ssgi_reproject(prev_view_proj, history, p, texel, w)) return vec4(0.0);
    vec3 h = texelFetch(history, texel, 0).rgb;
    return vec4(clamp(h, vec3(0.0), vec3(pc.feedback_max_w_m2)), w);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(p, size))) return;
    float depth = texelFetch(gb_depth, p, 0).r;
    if (depth >= 1.0) {
        imageStore(out_pos, p, vec4(0.0));
        imageStore(out_nrm, p, vec4(0.0));
        imageStore(out_color, p, vec4(0.0));
        imageStore(out_reprojected, p, vec4(0.0));
        return;
    }
    vec3 wp = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, p, vec2(size), depth);
    float z = max(dot(wp - frame.camera_position.xyz, ssgi_camera_forward(frame.inv_view_proj)), 1e-4);
    vec3 n = normalize(texelFetch(gb_normal, p, 0).xyz);
    vec3 color = texelFetch(direct, p, 0).rgb;
    vec4 previous = reprojected_irradiance(wp);
    if (FEEDBACK) {
        vec3 albedo = texelFetch(gb_albedo, p, 0).rgb;
        color += albedo / SSGI_PI * previous.a * previous.rgb;
    }
    imageStore(out_reprojected, p, previous);
    imageStore(out_pos, p, vec4(wp, z));
    imageStore(out_nrm, p, vec4(n, 0.0));
    imageStore(out_color, p, vec4(color, 1.0));
}

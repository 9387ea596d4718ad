#version 450
// G-buffer channels as a debug view: the albedo, world-space normal or camera distance that
// the lit image is computed from. `value` holds the channel itself (albedo, normal xyz, or the
// distance in meters; alpha 1 on geometry, 0 on background), `color` a picture of it.

#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_albedo;
layout(set = 0, binding = 2) uniform sampler2D gb_normal;
layout(set = 0, binding = 3) uniform sampler2D gb_depth;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D value;
layout(set = 0, binding = 5, rgba8) uniform writeonly image2D color;

layout(push_constant) uniform Push {
    uint channel;          // 0 albedo, 1 normal, 2 distance
    float inv_distance_m;  // distance shown black: 1 / this (the scene's diagonal)
} pc;

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(value);
    if (any(greaterThanEqual(px, size))) {
        return;
    }
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        // Background: the depth buffer's clear value.
        imageStore(value, px, vec4(0.0));
        imageStore(color, px, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec3 v;
    vec3 c;
    if (pc.channel == 0u) {
        v = texelFetch(gb_albedo, px, 0).rgb;
        c = srgb_encode(v);
    } else if (pc.channel == 1u) {
        v = normalize(texelFetch(gb_normal, px, 0).xyz);
        c = v * 0.5 + 0.5;
    } else {
        vec2 ndc = (vec2(px) + 0.5) / vec2(size) * 2.0 - 1.0;
        vec4 wp = frame.inv_view_proj * vec4(ndc, depth, 1.0);
        // Camera-relative (pixel_world_position): the distance, or the view depth under
        // orthographic projection.
        vec3 rel = wp.xyz / wp.w;
        float d = frame_orthographic(frame.camera_forward) ? dot(rel, frame.camera_forward.xyz) : length(rel);
        v = vec3(d);
        c = vec3(clamp(1.0 - d * pc.inv_distance_m, 0.0, 1.0));
    }
    imageStore(value, px, vec4(v, 1.0));
    imageStore(color, px, vec4(c, 1.0));
}

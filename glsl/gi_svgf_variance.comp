#version 450
// SVGF's variance estimate (Schied et al. 2017 §4.2), the input of its à-trous iterations
// (gi_svgf.comp): copies the indirect light and writes, in alpha, the variance of each pixel's
// luminance estimate.
//
// TEMPORAL (under gi_temporal): a pixel of n >= MIN_FRAMES frames has the variance of its mean,
// (E[l^2] - E[l]^2) / n, from its moments. As in gi_filter.comp (and unlike Schied et al., who
// keep the variance of one sample) it is the mean's, so that the filter steps back as frames
// accumulate and a long render converges to the method's own image.
// Otherwise (no history, or fewer frames): the variance of the luminance over the 7×7 pixels
// around, weighted by the filter's geometric weights (same surface, same lobe kind), which is
// the variance of one pixel's estimate plus the light's own variation over the window.
#include "frame.glsl"
#include "filter_lobes.glsl"

layout(constant_id = 0) const bool GLOSSY = false;
layout(constant_id = 1) const bool TEMPORAL = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform sampler2D src;          // TEMPORAL: a = frames n
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D dst;
layout(set = 0, binding = 5) uniform sampler2D gb_specular;  // the normals when !GLOSSY
layout(set = 0, binding = 6) uniform sampler2D moments;      // TEMPORAL: x = mean l^2

// Below 4 frames the moments say little about the variance (Schied et al. 2017 §4.2).
const float MIN_FRAMES = 4.0;

layout(push_constant) uniform Push {
    float plane_tolerance;  // relative to the distance to the camera (footprint_distance)
} pc;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    vec4 c0 = texelFetch(src, px, 0);
    if (texelFetch(gb_depth, px, 0).r >= 1.0) {
        imageStore(dst, px, vec4(c0.rgb, 0.0));
        return;
    }
    if (TEMPORAL && c0.a >= MIN_FRAMES) {
        float m1 = luminance(c0.rgb);
        float var = max(texelFetch(moments, px, 0).x - m1 * m1, 0.0) / c0.a;
        imageStore(dst, px, vec4(c0.rgb, var));
        return;
    }
    vec3 n0 = normalize(texelFetch(gb_normal, px, 0).xyz);
    vec3 p0 = world_at(px, vec2(size));
    float scale = pc.plane_tolerance * max(footprint_distance(frame.camera_position, frame.camera_forward, p0), 1e-6);
    int kind0 = GLOSSY ? lobe_kind(texelFetch(gb_specular, px, 0)) : 0;
    float w_sum = 0.0, l_sum = 0.0, l2_sum = 0.0;
    for (int dy = -3; dy <= 3; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            if (texelFetch(gb_depth, q, 0).r >= 1.0) continue;
            if (GLOSSY && lobe_kind(texelFetch(gb_specular, q, 0)) != kind0) continue;
            vec3 n1 = normalize(texelFetch(gb_normal, q, 0).xyz);
            float plane = abs(dot(n0, world_at(q, vec2(size)) - p0)) / scale;
            float w = pow(max(dot(n0, n1), 0.0), 128.0) * exp(-plane * plane);
            float l = luminance(texelFetch(src, q, 0).rgb);
            w_sum += w;
            l_sum += w * l;
            l2_sum += w * l * l;
        }
    }
    float m1 = l_sum / max(w_sum, 1e-30);
    float var = max(l2_sum / max(w_sum, 1e-30) - m1 * m1, 0.0);
    imageStore(dst, px, vec4(c0.rgb, var));
}

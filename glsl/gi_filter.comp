#version 450
// Geometry-aware filter (Herzog et al. 2010 as used in Thiedemann 2010, §8.6.1): a separable joint
// bilateral blur of the indirect irradiance, weighted by a spatial Gaussian, normal
// similarity and distance from the center pixel's tangent plane. Run horizontally, then
// vertically, `passes` times.
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform sampler2D src;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D dst;

layout(push_constant) uniform Push {
    ivec2 direction;
    int radius;
    float plane_tolerance;  // relative to the distance to the camera (footprint_distance)
} pc;

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, depth);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    if (texelFetch(gb_depth, px, 0).r >= 1.0 || pc.radius <= 0) {
        imageStore(dst, px, texelFetch(src, px, 0));
        return;
    }
    vec3 n0 = normalize(texelFetch(gb_normal, px, 0).xyz);
    vec3 p0 = world_at(px, vec2(size));
    float scale = pc.plane_tolerance * max(footprint_distance(frame.camera_position, frame.camera_forward, p0), 1e-6);
    float sigma = max(float(pc.radius) * 0.5, 0.5);
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int k = -pc.radius; k <= pc.radius; ++k) {
        ivec2 q = px + pc.direction * k;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
        if (texelFetch(gb_depth, q, 0).r >= 1.0) continue;
        vec3 n1 = normalize(texelFetch(gb_normal, q, 0).xyz);
        float wn = pow(max(dot(n0, n1), 0.0), 16.0);
        float plane = abs(dot(n0, world_at(q, vec2(size)) - p0)) / scale;
        float w = exp(-0.5 * float(k * k) / (sigma * sigma)) * wn * exp(-plane * plane);
        sum += w * texelFetch(src, q, 0).rgb;
        wsum += w;
    }
    imageStore(dst, px, vec4(wsum > 0.0 ? sum / wsum : texelFetch(src, px, 0).rgb, 1.0));
}

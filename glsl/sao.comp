#version 450
// Scalable Ambient Obscurance as modified by Oetke 2017 §2.5 (after McGuire, Mara and Luebke
// 2012): N = 16 taps on a spiral around each pixel, the estimator
//   A = max(0, 1 − 5/(r⁶N) Σ max(r² − v·v, 0)³ · max((v·n − β)/(v·v + ε), 0) · σ)^k
// with v = tap − centre (world space, meters), n the centre's G-buffer normal and σ the
// normal-similarity weight of the tap (Oetke 2017, Eq. 2.22). Runs at half resolution: the
// output texel (x, y) is the AO of full-resolution pixel (2x, 2y). Depth and normals come from
// the sao_depth pyramid: a tap at screen offset d pixels reads level
// m = clamp(⌊log2 d⌋ − LOG_Q, 0, levels − 1) (Oetke 2017 §2.5: q' = 2⁴; McGuire et al. 2012
// §3.1), the texel over its pixel there, and its position is the point at that texel's view
// depth on the tap pixel's own camera ray. Taps within 2^(LOG_Q+1) pixels read level 0, the
// full-resolution depth. 1 = unoccluded; the background is 1.
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
// The sao_depth pyramid, one binding per level: world normal (xyz) and view depth z (w; 0:
// sky). Levels beyond pc.depth_levels − 1 are bound to the coarsest and never read.
layout(set = 0, binding = 1) uniform sampler2D level0;
layout(set = 0, binding = 2) uniform sampler2D level1;
layout(set = 0, binding = 3) uniform sampler2D level2;
layout(set = 0, binding = 4) uniform sampler2D level3;
layout(set = 0, binding = 5) uniform sampler2D level4;
layout(set = 0, binding = 6) uniform sampler2D level5;
layout(set = 0, binding = 7, r32f) uniform writeonly image2D ao;

// log2 of the screen offset (pixels) up to which a tap reads level 0, minus one.
const int LOG_Q = 4;

layout(push_constant) uniform Push {
    float radius_m;         // r: world-space sample radius
    float bias;             // β
    float contrast;         // k: the exponent
    float epsilon_m2;       // ε, m²
    float px_per_m_at_1m;   // S': height in pixels of a 1 m object at 1 m view depth
    uint taps;              // N
    float spiral_turns;     // τ
    uint seed;              // varies the per-pixel rotation φ
    uint depth_levels;      // levels of the sao_depth pyramid (at most 6)
} pc;

#define TWO_PI 6.28318530717958647692

// Level m of the pyramid at texel q (m < pc.depth_levels). Each level is its own binding (a
// one-level view), read at level 0: with one binding and texelFetch's level varying between
// neighbouring invocations, llvmpipe (lavapipe) returned texels of the wrong level, which put
// taps at far pixels' depths (measured: v·n up to 0.07 m on a flat floor, where it is 0; a
// switch over constant levels of the one binding did the same).
vec4 pyramid_texel(ivec2 q, int m) {
    switch (m) {
        case 0: return texelFetch(level0, min(q, textureSize(level0, 0) - 1), 0);
        case 1: return texelFetch(level1, min(q, textureSize(level1, 0) - 1), 0);
        case 2: return texelFetch(level2, min(q, textureSize(level2, 0) - 1), 0);
        case 3: return texelFetch(level3, min(q, textureSize(level3, 0) - 1), 0);
        case 4: return texelFetch(level4, min(q, textureSize(level4, 0) - 1), 0);
        default: return texelFetch(level5, min(q, textureSize(level5, 0) - 1), 0);
    }
}

// The point at view depth z on the camera ray through pixel px's centre (under orthographic
// projection the rays are parallel to `forward`, each through its own pixel).
vec3 world_at(ivec2 px, vec2 size, float z, vec3 forward) {
    if (frame_orthographic(frame.camera_forward)) {
        vec3 q = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, 0.5);
        return q + forward * (z - dot(q - frame.camera_position.xyz, forward));
    }
    vec3 d = pixel_world_position(frame.inv_view_proj, vec3(0.0), px, size, 0.5);
    return frame.camera_position.xyz + d * (z / dot(d, forward));
}

// The camera's unit view direction, from the clip-space z axis.
vec3 camera_forward() {
    vec4 a = frame.inv_view_proj * vec4(0.0, 0.0, 0.0, 1.0);
    vec4 b = frame.inv_view_proj * vec4(0.0, 0.0, 1.0, 1.0);
    return normalize(b.xyz / b.w - a.xyz / a.w);
}

// φ: a per-pixel rotation in [0, 2π) from an integer hash of the pixel (Jenkins-style
// mixing; McGuire 2012 uses (3x ^ y + xy) · 10, which leaves visible patterns at half res).
float rotation(uvec2 p) {
    uint h = p.x * 1973u + p.y * 9277u + pc.seed * 26699u;
    h = (h ^ (h >> 16)) * 0x7feb352du;
    h = (h ^ (h >> 15)) * 0x846ca68bu;
    h ^= h >> 16;
    return float(h >> 8) * (TWO_PI / 16777216.0);
}

// Oetke 2017, Eq. 2.22: boosts near-parallel occluders, damps those near 90°.
float normal_similarity(float c) {
    return smoothstep(0.01, 0.2, c) * 0.6 + 0.4 + smoothstep(0.8, 1.0, c) * 2.0;
}

void main() {
    ivec2 hp = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(hp, imageSize(ao)))) return;
    ivec2 size = ivec2(frame.counts.zw);
    ivec2 c = min(hp * 2, size - 1);
    vec4 centre = texelFetch(level0, c, 0);
    if (centre.w <= 0.0) {
        imageStore(ao, hp, vec4(1.0));
        return;
    }
    vec3 forward = camera_forward();
    vec3 p = world_at(c, vec2(size), centre.w, forward);
    vec3 n = centre.xyz;
    float z_m = max(centre.w, 1e-4);
    int top = int(pc.depth_levels) - 1;
    float r = pc.radius_m;
    float r2 = r * r;
    // r' = r·S'/z: the radius in pixels (Eq. 2.20); under orthographic projection a meter
    // spans height / ortho height pixels at every depth.
    float radius_px = frame_orthographic(frame.camera_forward)
        ? r * float(size.y) / frame.camera_forward.w
        : r * pc.px_per_m_at_1m / z_m;
    float phi = rotation(uvec2(c));
    float sum = 0.0;
    for (uint i = 0u; i < pc.taps; ++i) {
        float alpha = (float(i) + 0.5) / float(pc.taps);
        float theta = TWO_PI * alpha * pc.spiral_turns + phi;
        float offset_px = radius_px * alpha;
        ivec2 s = ivec2(floor(vec2(c) + 0.5 + offset_px * vec2(cos(theta), sin(theta))));
        if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, size))) continue;
        int m = clamp(findMSB(int(min(offset_px, 1e9))) - LOG_Q, 0, top);
        vec4 tap = pyramid_texel(s >> m, m);
        if (tap.w <= 0.0) continue;
        vec3 v = world_at(s, vec2(size), tap.w, forward) - p;
        float vv = dot(v, v);
        float f = max(r2 - vv, 0.0);
        vec3 ns = tap.xyz;
        float sigma = normal_similarity(abs(dot(n, ns)));
        sum += f * f * f * max((dot(v, n) - pc.bias) / (vv + pc.epsilon_m2), 0.0) * sigma;
    }
    float a = max(0.0, 1.0 - 5.0 / (r2 * r2 * r2 * float(pc.taps)) * sum);
    imageStore(ao, hp, vec4(pow(a, pc.contrast)));
}

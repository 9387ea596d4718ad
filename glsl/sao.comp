#version 450
// Scalable Ambient Obscurance as modified by Oetke 2017 §2.5 (after McGuire, Mara and Luebke
// 2012): N = 16 taps on a spiral around each pixel, the estimator
//   A = max(0, 1 − 5/(r⁶N) Σ max(r² − v·v, 0)³ · max((v·n − β)/(v·v + ε), 0) · σ)^k
// with v = tap − centre (world space, meters), n the centre's G-buffer normal and σ the
// normal-similarity weight of the tap (Oetke 2017, Eq. 2.22). Runs at half resolution: the
// output texel (x, y) is the AO of full-resolution pixel (2x, 2y). Depth and normals are read
// at full resolution (level 0; the thesis's per-tap depth mips are not built). 1 = unoccluded;
// the background is 1.
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D ao;

layout(push_constant) uniform Push {
    float radius_m;         // r: world-space sample radius
    float bias;             // β
    float contrast;         // k: the exponent
    float epsilon_m2;       // ε, m²
    float px_per_m_at_1m;   // S': height in pixels of a 1 m object at 1 m view depth
    uint taps;              // N
    float spiral_turns;     // τ
    uint seed;              // varies the per-pixel rotation φ
} pc;

#define TWO_PI 6.28318530717958647692

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, depth);
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
    if (texelFetch(gb_depth, c, 0).r >= 1.0) {
        imageStore(ao, hp, vec4(1.0));
        return;
    }
    vec3 p = world_at(c, vec2(size));
    vec3 n = normalize(texelFetch(gb_normal, c, 0).xyz);
    float z_m = max(dot(p - frame.camera_position.xyz, camera_forward()), 1e-4);
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
        ivec2 s = ivec2(floor(vec2(c) + 0.5 + radius_px * alpha * vec2(cos(theta), sin(theta))));
        if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, size))) continue;
        if (texelFetch(gb_depth, s, 0).r >= 1.0) continue;
        vec3 v = world_at(s, vec2(size)) - p;
        float vv = dot(v, v);
        float f = max(r2 - vv, 0.0);
        vec3 ns = normalize(texelFetch(gb_normal, s, 0).xyz);
        float sigma = normal_similarity(abs(dot(n, ns)));
        sum += f * f * f * max((dot(v, n) - pc.bias) / (vv + pc.epsilon_m2), 0.0) * sigma;
    }
    float a = max(0.0, 1.0 - 5.0 / (r2 * r2 * r2 * float(pc.taps)) * sum);
    imageStore(ao, hp, vec4(pow(a, pc.contrast)));
}

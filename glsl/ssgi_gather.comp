#version 450
// One level of the screen-space diffuse gather (Oetke 2017 §2.3, §5.2; SHR10): the indirect
// irradiance a texel receives from the texels of its ring on this level, plus (HAS_COARSER)
// the coarser levels' result, joint-bilaterally upsampled. Each coarser level covers the ring
// of twice the radius, so the levels together tile the screen: level k gathers over
// r ∈ [R/2, R) of its own texels (R·2^(k−1) to R·2^k pixels), the finest level over the
// whole disk r ∈ [inner, R).
//
// A sender texel s contributes (Eq. 2.12, visibility v = 1 as in the thesis)
//   E += L_s · cos⁺θ · cos⁺θ' · ds / (‖x − x_s‖² + 0.1 m²)
// with the patch area of Eq. 2.10, ds = 4 tan(f_h/2) tan(f_v/2) · 4^k / (W·H) · z² · cos α /
// cos β (z the view depth, α the angle between the view ray and the camera axis, β between
// the view ray and the sender's normal; the ratio clamped to [0.001, 1000] as in the thesis).
// The samples lie on a spiral uniform in area over the ring (radius √(mix(r0², r1², t))), so
// each stands for π(r1² − r0²)/N texels: an unbiased estimate of the on-screen integral
// (the thesis instead spaces radii linearly and scales levels by 2^(2k) and 128/N).
// Samples off the screen or on sky contribute nothing.
#include "frame.glsl"
#include "ssgi.glsl"

layout(constant_id = 0) const bool HAS_COARSER = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D lvl_pos;
layout(set = 0, binding = 2) uniform sampler2D lvl_nrm;
layout(set = 0, binding = 3) uniform sampler2D lvl_color;
layout(set = 0, binding = 4) uniform sampler2D coarse_value;   // lvl_pos without HAS_COARSER
layout(set = 0, binding = 5) uniform sampler2D coarse_pos;
layout(set = 0, binding = 6) uniform sampler2D coarse_nrm;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D out_irradiance;

layout(push_constant) uniform Push {
    float ds_factor;       // 4 tan(f_h/2) tan(f_v/2) 4^k / (W H): a texel's area per z², facing
    float radius_texels;   // R
    float inner_texels;    // r0: R/2, or the finest level's inner radius
    uint samples;          // N
    uint seed;             // varies the spiral's start angle per texel and frame
    float spiral_turns;
} pc;

// Oetke 2017 Eq. 2.12: the regularization of the 1/r² term, m².
const float DIST2_REG_M2 = 0.1;

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(out_irradiance);
    if (any(greaterThanEqual(q, size))) return;
    vec4 pz = texelFetch(lvl_pos, q, 0);
    if (pz.w <= 0.0) {
        imageStore(out_irradiance, q, vec4(0.0));
        return;
    }
    vec3 x = pz.xyz;
    vec3 n = texelFetch(lvl_nrm, q, 0).xyz;
    vec3 e = vec3(0.0);
    if (HAS_COARSER) {
        e = ssgi_joint_bilateral(coarse_value, coarse_pos, coarse_nrm, q, 2.0, n, pz.w);
    }
    vec3 cam = frame.camera_position.xyz;
    vec3 fwd = ssgi_camera_forward(frame.inv_view_proj);
    float r0sq = pc.inner_texels * pc.inner_texels;
    float r1sq = pc.radius_texels * pc.radius_texels;
    float texels_per_sample = SSGI_PI * (r1sq - r0sq) / float(pc.samples);
    float phi = 2.0 * SSGI_PI * ssgi_hash(uvec2(q), pc.seed);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < pc.samples; ++i) {
        float t = (float(i) + 0.5) / float(pc.samples);
        float r = sqrt(mix(r0sq, r1sq, t));
        float a = phi + 2.0 * SSGI_PI * pc.spiral_turns * t;
        ivec2 s = ivec2(floor(vec2(q) + 0.5 + r * vec2(cos(a), sin(a))));
        if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, size))) continue;
        vec4 sz = texelFetch(lvl_pos, s, 0);
        if (sz.w <= 0.0) continue;
        vec3 d = sz.xyz - x;
        float d2 = dot(d, d);
        if (d2 <= 0.0) continue;
        vec3 dir = d * inversesqrt(d2);
        vec3 ns = texelFetch(lvl_nrm, s, 0).xyz;
        float cos_r = max(dot(n, dir), 0.0);
        float cos_s = max(-dot(ns, dir), 0.0);
        if (cos_r * cos_s <= 0.0) continue;
        // Eq. 2.10: the sender texel's area.
        vec3 v = sz.xyz - cam;
        float v_len = length(v);
        float cos_alpha = dot(v, fwd) / v_len;
        float cos_beta = abs(dot(v, ns)) / v_len;
        float ds = pc.ds_factor * sz.w * sz.w * clamp(cos_alpha / max(cos_beta, 1e-6), 0.001, 1000.0);
        vec3 l = texelFetch(lvl_color, s, 0).rgb;
        sum += l * (cos_r * cos_s * ds / (d2 + DIST2_REG_M2));
    }
    imageStore(out_irradiance, q, vec4(e + max(sum * texels_per_sample, vec3(0.0)), 1.0));
}

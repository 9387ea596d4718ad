#version 450
// The screen-space GI's last step (Oetke 2017 §5.2, §5.5): the irradiance of the GI
// resolution joint-bilaterally upsampled to the frame against the full-resolution G-buffer
// geometry (level 0 of the pyramid). Writes the indirect image gi_filter and gi_composite
// read (irradiance; at Phong pixels the diffuse radiance ρ_d/π·E, which the composite adds as
// stored), the history the next frame's feedback reprojects (irradiance and the pixel's clip
// w), and this frame's camera as the next frame's previous camera. The irradiance is blended
// with the reprojected history, E = mix(E_new, E_history, τ·w) (Oetke 2017 §5.1: history
// weight τ, w the depth agreement), which averages the spiral's per-frame noise.
// GGX pixels (HAS_GGX) get their indirect radiance by Eq. 2.19 with the split-sum table:
//   L = C·E·(1 − F0·A)/π + L_spec·(F0·A + B),
// C the G-buffer's diffuse colour, A and B at (n·v, roughness). L_spec, the specular incoming
// light: without SSR the diffuse fallback of Oetke 2017 §5.4 everywhere, the uniform radiance
// E/π that gives the gathered irradiance E (the thesis scales by 1/(4π²)); with SSR the
// reflection rays' (a·L, a) completed by the fallback, L_spec = a·L + (1 − a)·E/π.
// With SSR, Phong pixels add L_spec times their lobe's directional albedo,
//   ∫ ρs (n+2)/(2π) cos^n α (n·l) dl = ρs (n·v)
// (l about the mirror direction r: the φ integral leaves (n·r) cos α of n·l, and
// ∫ cos^(n+1) α sin α dα · 2π = 2π/(n+2); n·r = n·v; exact while the lobe stays above the
// horizon, an upper bound at grazing view).
#include "frame.glsl"
#include "ssgi.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 2) const bool SSR = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D coarse_value;
layout(set = 0, binding = 2) uniform sampler2D coarse_pos;
layout(set = 0, binding = 3) uniform sampler2D coarse_nrm;
layout(set = 0, binding = 4) uniform sampler2D fine_pos;
layout(set = 0, binding = 5) uniform sampler2D fine_nrm;
layout(set = 0, binding = 6) uniform sampler2D gb_albedo;
layout(set = 0, binding = 7) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 8, rgba32f) uniform writeonly image2D out_indirect;
layout(set = 0, binding = 9, rgba32f) uniform writeonly image2D history;
layout(set = 0, binding = 10, std430) writeonly buffer PrevCamera { mat4 prev_view_proj; };
layout(set = 0, binding = 11) uniform sampler2D gb_normal;    // w: GGX roughness
layout(set = 0, binding = 12) uniform sampler2D brdf_lut;     // A, B; albedo when !HAS_GGX
#include "gbuffer_lobe.glsl"

layout(set = 0, binding = 13) uniform sampler2D reprojected;  // rgb history, a weight
layout(set = 0, binding = 14) uniform sampler2D ssr;          // (a·L, a); albedo when !SSR

layout(push_constant) uniform Push {
    float scale;            // frame pixels per GI texel
    float history_weight;   // τ
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(out_indirect);
    if (p == ivec2(0)) prev_view_proj = frame.view_proj;
    if (any(greaterThanEqual(p, size))) return;
    vec4 pz = texelFetch(fine_pos, p, 0);
    if (pz.w <= 0.0) {
        imageStore(out_indirect, p, vec4(0.0));
        imageStore(history, p, vec4(0.0));
        return;
    }
    vec3 n = texelFetch(fine_nrm, p, 0).xyz;
    vec3 e = ssgi_joint_bilateral(coarse_value, coarse_pos, coarse_nrm, p, pc.scale, n, pz.w);
    vec4 previous = texelFetch(reprojected, p, 0);
    e = mix(e, previous.rgb, pc.history_weight * previous.a);
    vec4 clip = frame.view_proj * vec4(pz.xyz, 1.0);
    imageStore(history, p, vec4(e, clip.w));
    bool phong = HAS_PHONG && any(greaterThan(gbuffer_phong_specular(gb_specular, p), vec3(0.0)));
    vec3 out_value = phong ? texelFetch(gb_albedo, p, 0).rgb / SSGI_PI * e : e;
    vec4 lobe = texelFetch(gb_specular, p, 0);
    vec3 l_spec = e / SSGI_PI;
    if (SSR) {
        vec4 traced = texelFetch(ssr, p, 0);
        l_spec = traced.rgb + (1.0 - traced.a) * l_spec;
    }
    vec3 v = normalize(frame.camera_position.xyz - pz.xyz);
    float n_dot_v = clamp(dot(n, v), 0.0, 1.0);
    if (SSR && phong) out_value += l_spec * lobe.rgb * n_dot_v;
    if (HAS_GGX && lobe.a > 1.5) {
        float roughness = clamp(texelFetch(gb_normal, p, 0).w, 0.0, 1.0);
        ivec2 lut_size = textureSize(brdf_lut, 0);
        ivec2 t = min(ivec2(vec2(n_dot_v, roughness) * vec2(lut_size)), lut_size - 1);
        vec2 ab = texelFetch(brdf_lut, t, 0).rg;
        vec3 f0 = lobe.rgb;
        vec3 c = texelFetch(gb_albedo, p, 0).rgb;
        out_value = c * e * (1.0 - f0 * ab.x) / SSGI_PI + l_spec * (f0 * ab.x + ab.y);
    }
    imageStore(out_indirect, p, vec4(out_value, 1.0));
}

#version 450
// The split-sum BRDF table (Karis 2013, Oetke 2017 §2.4 Eq. 2.17–2.18, §5.4): texel (i, j)
// holds, for n·v = (i + 0.5)/W and roughness r = (j + 0.5)/H, the scale A and bias B of F0 in
//   ∫ f_spec(l, v) (n·l) dl = F0·A + B,
// for voxgi's GGX lobe (D GGX with α = r², exact separable Smith G1, Schlick Fresnel; the
// thesis's code uses Smith-Schlick with k = α²/2 instead). 1024 Hammersley directions per
// texel, importance-sampled by D(h)(n·h): each sample weighs G(l)G(v)(v·h)/((n·h)(n·v)),
// split by the Fresnel term into (1 − F_c) for A and F_c for B, F_c = (1 − v·h)⁵.
#include "brdf.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform writeonly image2D lut;

layout(push_constant) uniform Push {
    uint samples;
} pc;

float radical_inverse(uint b) {
    b = (b << 16u) | (b >> 16u);
    b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
    b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
    b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
    b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
    return float(b) * 2.3283064365386963e-10;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(lut);
    if (any(greaterThanEqual(p, size))) return;
    float n_dot_v = (float(p.x) + 0.5) / float(size.x);
    float roughness = (float(p.y) + 0.5) / float(size.y);
    float alpha = roughness * roughness;
    vec3 v = vec3(sqrt(1.0 - n_dot_v * n_dot_v), 0.0, n_dot_v);
    float a = 0.0, b = 0.0;
    for (uint k = 0u; k < pc.samples; ++k) {
        vec2 u = vec2((float(k) + 0.5) / float(pc.samples), radical_inverse(k));
        float phi = 2.0 * PI * u.y;
        float cos_h = sqrt((1.0 - u.x) / (1.0 + (alpha * alpha - 1.0) * u.x));
        float sin_h = sqrt(1.0 - cos_h * cos_h);
        vec3 h = vec3(sin_h * cos(phi), sin_h * sin(phi), cos_h);
        float v_dot_h = dot(v, h);
        vec3 l = 2.0 * v_dot_h * h - v;
        if (l.z <= 0.0 || v_dot_h <= 0.0) continue;
        float g_vis = ggx_g1(alpha, l.z) * ggx_g1(alpha, n_dot_v) * v_dot_h / (cos_h * n_dot_v);
        float fc = pow(1.0 - v_dot_h, 5.0);
        a += (1.0 - fc) * g_vis;
        b += fc * g_vis;
    }
    imageStore(lut, p, vec4(a, b, 0.0, 0.0) / float(pc.samples));
}

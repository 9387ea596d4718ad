#version 450
// One à-trous iteration of SVGF (Schied et al. 2017 §4.4; Dammertz et al. 2010): 5×5 taps at
// spacing 2^i, the B3-spline kernel h = (1/16, 1/4, 3/8, 1/4, 1/16) per axis, each tap weighed
// by edge-stopping functions:
// - normal: max(0, n_p·n_q)^128 (σ_n = 128);
// - surface: exp(-(|n_p·(x_q - x_p)| / (0.02 d_p))^2), the distance of the tap's point from the
//   centre's tangent plane relative to the centre's distance (the geometry-aware filter's
//   test, in place of Schied's screen-space depth gradient: a tap 16 pixels away on the same
//   plane keeps its weight, one on a step does not);
// - luminance: exp(-|l_p - l_q| / (σ_l sqrt(g3x3(Var_p)) + ε)), σ_l = 4, the variance
//   averaged over the centre's 3×3 pixels by a Gaussian;
// - glossy scenes (GLOSSY): the lobe rules of filter_lobes.glsl, as in gi_filter.comp.
// The variance (alpha, from gi_svgf_variance.comp) is filtered along with the squared weights,
// Var' = Σ (w h)^2 Var_q / (Σ w h)^2, so each iteration's luminance weight sees the noise left.
#include "frame.glsl"
#include "filter_lobes.glsl"

layout(constant_id = 0) const bool GLOSSY = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform sampler2D src;          // a = variance of the luminance
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D dst;
layout(set = 0, binding = 5) uniform sampler2D gb_specular;  // the normals when !GLOSSY

// Schied et al. 2017 §4.4: σ_l = 4, σ_n = 128.
const float SIGMA_L = 4.0;
const float SIGMA_N = 128.0;

layout(push_constant) uniform Push {
    int step_px;            // 2^i
    float plane_tolerance;  // relative to the distance to the camera (footprint_distance)
    ivec2 tile_px;          // glossy pixels: taps within the VPL tile skip the mirror weight
    int last;               // 1: the last iteration writes alpha 1, as gi_filter.comp does
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
        imageStore(dst, px, vec4(c0.rgb, pc.last != 0 ? 1.0 : 0.0));
        return;
    }
    const float kernel[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
    float g_var = 0.0, g_sum = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            if (texelFetch(gb_depth, q, 0).r >= 1.0) continue;
            // (1/4, 1/2, 1/4) per axis.
            float g = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
            g_var += g * texelFetch(src, q, 0).a;
            g_sum += g;
        }
    }
    float sigma = SIGMA_L * sqrt(g_var / max(g_sum, 1e-30));
    float l0 = luminance(c0.rgb);
    vec3 n0 = normalize(texelFetch(gb_normal, px, 0).xyz);
    vec3 p0 = world_at(px, vec2(size));
    float scale = pc.plane_tolerance * max(footprint_distance(frame.camera_position, frame.camera_forward, p0), 1e-6);
    int kind0 = 0;
    vec3 mirror0 = vec3(0.0);
    float theta0 = 1.0;
    if (GLOSSY) {
        kind0 = lobe_kind(texelFetch(gb_specular, px, 0));
        mirror0 = reflect(-toward_camera(frame.camera_position, frame.camera_forward, p0), n0);
        if (kind0 != 0) theta0 = lobe_half_angle(kind0, texelFetch(gb_normal, px, 0).w);
    }
    vec3 sum = vec3(0.0);
    float w_sum = 0.0, var_sum = 0.0;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            ivec2 d = ivec2(dx, dy) * pc.step_px;
            ivec2 q = px + d;
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            if (texelFetch(gb_depth, q, 0).r >= 1.0) continue;
            vec4 c = texelFetch(src, q, 0);
            float w = kernel[abs(dx)] * kernel[abs(dy)];
            if (dx != 0 || dy != 0) {
                vec3 n1 = normalize(texelFetch(gb_normal, q, 0).xyz);
                vec3 p1 = world_at(q, vec2(size));
                float plane = abs(dot(n0, p1 - p0)) / scale;
                w *= pow(max(dot(n0, n1), 0.0), SIGMA_N) * exp(-plane * plane);
                // 1e-6 of the luminance keeps a noiseless pixel from dividing by zero.
                w *= exp(-abs(luminance(c.rgb) - l0) / (sigma + 1e-6 * l0 + 1e-30));
                if (GLOSSY) {
                    if (lobe_kind(texelFetch(gb_specular, q, 0)) != kind0) continue;
                    if (kind0 != 0 && (abs(d.x) >= pc.tile_px.x || abs(d.y) >= pc.tile_px.y)) {
                        vec3 mirror1 = reflect(-toward_camera(frame.camera_position, frame.camera_forward, p1), n1);
                        float delta = acos(clamp(dot(mirror0, mirror1), -1.0, 1.0)) / theta0;
                        w *= exp(-0.5 * delta * delta);
                    }
                }
            }
            sum += w * c.rgb;
            w_sum += w;
            var_sum += w * w * c.a;
        }
    }
    // The centre's own weight is h(0)^2 > 0, so w_sum > 0.
    float var = var_sum / (w_sum * w_sum);
    imageStore(dst, px, vec4(sum / w_sum, pc.last != 0 ? 1.0 : var));
}

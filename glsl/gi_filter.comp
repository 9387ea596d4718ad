#version 450
// Geometry-aware filter (Herzog et al. 2010 as used in Thiedemann 2010, §8.6.1): a separable joint
// bilateral blur of the indirect irradiance, weighted by a spatial Gaussian, normal
// similarity and distance from the center pixel's tangent plane. Run horizontally, then
// vertically, `passes` times.
//
// Glossy scenes (GLOSSY: the G-buffer has a lobe target): Phong and GGX pixels hold their
// indirect radiance, which depends on the lobe and on the view, not irradiance. A pixel then
// averages only pixels of its own lobe kind (Lambert irradiance never mixes with glossy
// radiance), and a glossy pixel only neighbours whose mirror directions lie within its lobe:
// the weight exp(-(delta / theta)^2 / 2), delta the angle between the two pixels' mirror
// directions of the view ray, theta the lobe's half-maximum angle about the mirror direction
// (Phong cos^n: cos theta = 2^(-1/n); GGX through the exponent n = 2 / alpha^2 - 2 of the same
// width, as ssgi_reflect.comp's cone). A rough lobe (wide theta) is blurred by the other weights alone; a sharp one (a
// mirror's reflection, a curved metal whose mirror direction turns fast) keeps its detail.
// Except within the VPLs' interleaving tile (|k| < tile_px, the pattern's side along this
// pass): there the pixels hold different VPL sets of one estimate, which the filter has to
// merge (Thiedemann 2010 §7.3.2) whatever the lobe; elsewhere tile_px = 1.
//
// VARIANCE_GUIDED (under temporal accumulation, gi_temporal.comp): a tap also weighs
// exp(-|l_p - l_q| / (SIGMA_L sigma_p)), l the luminance and sigma_p the standard error of
// the centre pixel's accumulated mean, sqrt(var / n) from its moments and history length n
// (Schied et al. 2017 §4.3 use the variance of one sample; the mean's makes the filter step
// back as frames accumulate, so that a long render converges to the method's own image, not
// the filter's), averaged over the centre's 3×3 pixels. Pixels with fewer than MIN_FRAMES
// frames have no usable moments and are filtered by the geometric weights alone.
#include "frame.glsl"
#include "filter_lobes.glsl"

layout(constant_id = 0) const bool GLOSSY = false;
layout(constant_id = 1) const bool VARIANCE_GUIDED = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform sampler2D src;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D dst;
layout(set = 0, binding = 5) uniform sampler2D gb_specular;  // the normals when !GLOSSY
layout(set = 0, binding = 6) uniform sampler2D accumulated;  // VARIANCE_GUIDED: a = frames n
layout(set = 0, binding = 7) uniform sampler2D moments;      // VARIANCE_GUIDED: x = mean l^2

// Schied et al. 2017 §4.3: sigma_l = 4, differences beyond four standard errors are edges.
const float SIGMA_L = 4.0;
// Below 4 frames the moments say little about the variance (Schied et al. 2017 §4.2).
const float MIN_FRAMES = 4.0;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

layout(push_constant) uniform Push {
    ivec2 direction;
    int radius;
    float plane_tolerance;  // relative to the distance to the camera (footprint_distance)
    int tile_px;            // glossy pixels: taps with |k| < tile_px skip the mirror weight
} pc;

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
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
    int kind0 = 0;
    vec3 mirror0 = vec3(0.0);
    float theta0 = 1.0;
    if (GLOSSY) {
        kind0 = lobe_kind(texelFetch(gb_specular, px, 0));
        mirror0 = reflect(-toward_camera(frame.camera_position, frame.camera_forward, p0), n0);
        if (kind0 != 0) theta0 = lobe_half_angle(kind0, texelFetch(gb_normal, px, 0).w);
    }
    // The centre's standard error of its mean luminance; negative: no luminance weight.
    float sigma_p = -1.0;
    float l0 = 0.0;
    if (VARIANCE_GUIDED && texelFetch(accumulated, px, 0).a >= MIN_FRAMES) {
        // The variance of the mean, averaged over the 3×3 pixels of enough frames around: a
        // few frames' moments of one pixel are a noisy estimate, and one that came out low
        // would keep that pixel's noise (Schied et al. 2017 §4.3 blur it the same way).
        float var_sum = 0.0, count = 0.0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                ivec2 q = clamp(px + ivec2(dx, dy), ivec2(0), size - 1);
                vec4 acc = texelFetch(accumulated, q, 0);
                if (acc.a < MIN_FRAMES || texelFetch(gb_depth, q, 0).r >= 1.0) continue;
                float m1 = luminance(acc.rgb);
                var_sum += max(texelFetch(moments, q, 0).x - m1 * m1, 0.0) / acc.a;
                count += 1.0;
            }
        }
        sigma_p = sqrt(var_sum / max(count, 1.0));
        l0 = luminance(texelFetch(src, px, 0).rgb);
    }
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int k = -pc.radius; k <= pc.radius; ++k) {
        ivec2 q = px + pc.direction * k;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
        if (texelFetch(gb_depth, q, 0).r >= 1.0) continue;
        vec3 n1 = normalize(texelFetch(gb_normal, q, 0).xyz);
        float wn = pow(max(dot(n0, n1), 0.0), 16.0);
        vec3 p1 = world_at(q, vec2(size));
        float plane = abs(dot(n0, p1 - p0)) / scale;
        float w = exp(-0.5 * float(k * k) / (sigma * sigma)) * wn * exp(-plane * plane);
        if (GLOSSY) {
            if (lobe_kind(texelFetch(gb_specular, q, 0)) != kind0) continue;
            if (kind0 != 0 && abs(k) >= pc.tile_px) {
                vec3 mirror1 = reflect(-toward_camera(frame.camera_position, frame.camera_forward, p1), n1);
                float delta = acos(clamp(dot(mirror0, mirror1), -1.0, 1.0)) / theta0;
                w *= exp(-0.5 * delta * delta);
            }
        }
        vec3 c = texelFetch(src, q, 0).rgb;
        if (VARIANCE_GUIDED && sigma_p >= 0.0 && k != 0) {
            // 1e-6 of the luminance keeps a noiseless pixel from dividing by zero.
            w *= exp(-abs(luminance(c) - l0) / (SIGMA_L * sigma_p + 1e-6 * l0 + 1e-30));
        }
        sum += w * c;
        wsum += w;
    }
    imageStore(dst, px, vec4(wsum > 0.0 ? sum / wsum : texelFetch(src, px, 0).rgb, 1.0));
}

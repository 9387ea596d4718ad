#version 450
// Deferred direct lighting: outgoing radiance (W/(m^2 sr)) of every G-buffer pixel from every
// light, with shadow-map visibility, plus the emitted radiance of emissive surfaces. Lambert
// f = rho/pi; normalized Phong only when the scene has Phong materials (HAS_PHONG), GGX only when
// it has GGX materials (HAS_GGX; gbuffer.frag has the encoding). Point/spot: E = I cos(theta) / d^2 times Mitsuba's spot
// falloff; directional: E = E_perp cos(theta).
#include "frame.glsl"
#include "brdf.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 2) const bool HAS_EMISSION = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#include "shadow.glsl"
layout(set = 0, binding = 1) uniform sampler2D gb_albedo;
layout(set = 0, binding = 2) uniform sampler2D gb_normal;
layout(set = 0, binding = 3) uniform sampler2D gb_specular;
layout(set = 0, binding = 4) uniform sampler2D gb_depth;
layout(set = 0, binding = 5) uniform sampler2DArray shadow_maps;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D radiance;
layout(set = 0, binding = 7) uniform sampler2D gb_emission;  // albedo when !HAS_EMISSION

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(radiance, px, vec4(0.0));
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec3 albedo = texelFetch(gb_albedo, px, 0).rgb;
    vec4 ns = texelFetch(gb_normal, px, 0);
    vec3 n = normalize(ns.xyz);
    vec3 wo = normalize(frame.camera_position.xyz - p);
    vec4 lobe = HAS_PHONG || HAS_GGX ? texelFetch(gb_specular, px, 0) : vec4(0.0);
    vec3 specular = lobe.rgb;
    bool ggx = HAS_GGX && lobe.a > 1.5;

    vec3 lo = vec3(0.0);
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight l = frame.lights[i];
        vec3 wi;
        vec3 e;
        if (l.info.x == LIGHT_DIRECTIONAL) {
            wi = -l.direction.xyz;
            e = l.intensity.rgb * max(dot(n, wi), 0.0);
        } else {
            vec3 d = l.position.xyz - p;
            float d2 = max(dot(d, d), 1e-30);
            wi = d * inversesqrt(d2);
            float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
            e = l.intensity.rgb * (falloff * max(dot(n, wi), 0.0) / d2);
        }
        if (all(equal(e, vec3(0.0)))) continue;
        float vis = direct_shadow_visibility(shadow_maps, l, p, n, max(dot(n, wi), 0.0));
        vec3 f;
        if (ggx) {
            f = brdf_ggx(albedo, specular, ns.w, n, wi, wo);
        } else {
            f = brdf_lambert(albedo);
            if (HAS_PHONG) f += brdf_phong(specular, ns.w, n, wi, wo);
        }
        lo += f * e * vis;
    }
    if (HAS_EMISSION) lo += texelFetch(gb_emission, px, 0).rgb;
    imageStore(radiance, px, vec4(lo, 1.0));
}

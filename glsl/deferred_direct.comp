#version 450
// Deferred direct lighting: outgoing radiance (W/(m^2 sr)) of every G-buffer pixel from every
// light, with shadow-map visibility (direct_light.glsl), plus the emitted radiance of emissive
// surfaces. Phong only when the scene has Phong materials (HAS_PHONG), GGX only when it has GGX
// materials (HAS_GGX; gbuffer.frag has the encoding). Pixels the G-buffer left empty (depth 1)
// show the environment seen along their camera ray (ENVIRONMENT; black without one).
#include "frame.glsl"
#include "brdf.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 2) const bool HAS_EMISSION = false;
layout(constant_id = 8) const uint ENVIRONMENT = 0u;  // environment.glsl's kinds

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#include "shadow.glsl"
#include "direct_light.glsl"
layout(set = 0, binding = 1) uniform sampler2D gb_albedo;
layout(set = 0, binding = 2) uniform sampler2D gb_normal;
layout(set = 0, binding = 3) uniform sampler2D gb_specular;
layout(set = 0, binding = 4) uniform sampler2D gb_depth;
layout(set = 0, binding = 5) uniform sampler2DArray shadow_maps;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D radiance;
layout(set = 0, binding = 7) uniform sampler2D gb_emission;  // albedo when !HAS_EMISSION
layout(set = 0, binding = 8) uniform sampler2D environment_map;  // albedo unless a map
#include "environment.glsl"

// The unit direction of pixel px's camera ray: along the view under orthographic projection,
// else from the camera through the pixel's center (any depth on the ray will do; 0.5 keeps
// clear of the far plane, where an infinite projection would unproject to w = 0).
vec3 camera_ray_direction(ivec2 px, vec2 size) {
    if (frame_orthographic(frame.camera_forward)) return frame.camera_forward.xyz;
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, 0.5);
    return normalize(p - frame.camera_position.xyz);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        // Alpha stays 0: the pixel holds no surface.
        vec3 background = ENVIRONMENT != ENVIRONMENT_NONE ? environment_radiance(camera_ray_direction(px, vec2(size))) : vec3(0.0);
        imageStore(radiance, px, vec4(background, 0.0));
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec3 albedo = texelFetch(gb_albedo, px, 0).rgb;
    vec4 ns = texelFetch(gb_normal, px, 0);
    vec3 n = normalize(ns.xyz);
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, p);
    vec4 lobe = HAS_PHONG || HAS_GGX ? texelFetch(gb_specular, px, 0) : vec4(0.0);
    vec3 lo = direct_radiance(shadow_maps, p, n, wo, albedo, lobe, ns.w);
    // The half-float emission is pre-exposed (gbuffer_frag.glsl); ×2^k restores it in f32.
    if (HAS_EMISSION) lo += texelFetch(gb_emission, px, 0).rgb * frame.radiance_scale.y;
    imageStore(radiance, px, vec4(lo, 1.0));
}

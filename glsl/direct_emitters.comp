#version 450
// Direct light from the emissive triangles and from the environment at every G-buffer pixel,
// with voxel visibility, added to deferred_direct's radiance (src/render/direct_emitters.rs
// says when the pass runs: without a GI method that brings this light itself).
//
// Emitters (HAS_EMITTERS): K light samples per pixel, each a triangle picked by power and a
// point uniformly on it (emitters.glsl, the path tracer's next-event estimation, shared),
// visibility by the voxel segment test. On Lambert pixels the sample is weighted 1 and
// evaluates the whole BRDF (emitter_sample's `parts` 3):
//   L_o = 1/K sum f(wi, wo) L cos_i cos_l / (d^2 p_A).
// On Phong and GGX pixels the specular part is combined by the power heuristic with K/2
// samples of the specular lobe that find their emitter by intersecting the emitter list
// (`parts` 4 and emitter_lobe_hit), the diffuse part stays light-sampled alone.
//
// Environment (ENVIRONMENT): K directions per pixel, sampled as the path tracer's first bounce
// samples the pixel's lobe (material_lobe.glsl's sample_lobe): Lambert pixels all cosine-
// distributed, Phong and GGX pixels half cosine, half from the specular lobe (stratified, each
// half its own estimator). A direction that leaves the voxel grid unblocked within the ray
// length brings the environment's radiance (environment_after_miss, as the GI rays):
//   L_o = 1/K_d sum rho_d w_d L_env + 1/K_s sum w_s L_env,
// w the lobe's f cos / pdf. With ENV_SAMPLING (`gi.env_sampling`, a map) K_e = round(alpha K)
// of the directions are drawn from the map's luminance instead (environment_sampling.glsl;
// alpha per map from how concentrated its power is: 1/2 for a sun, 0 for a smooth sky) and
// the rest split as above; each part of the BRDF is then an integral with two strategies,
// combined by the balance heuristic in its multi-sample form (Veach 1997, §9.2.2): every
// sample of either strategy weighs f L cos / (n_b p_b + K_e p_e), n_b p_b the part's own
// BSDF samples' count times density (docs/design/environment.md).
#include "frame.glsl"
#include "gi_common.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;  // the G-buffer has a lobe target (Phong or GGX)
layout(constant_id = 3) const bool HAS_EMITTERS = false;  // sample the emitter list (binding 14)
layout(constant_id = 8) const uint ENVIRONMENT = 0u;  // environment.glsl's kinds
// The frame accumulates (TAA): the pixel's sample rotation advances by the R2 sequence of the
// frame (gi.seed, counted per frame), so that the frames' sample sets interleave and their
// average converges; otherwise the rotation is fixed and a still image is the same every frame.
layout(constant_id = 9) const bool ADVANCE = false;
// Screen-space GI gathers the emission the camera sees (its lit colour includes it): the
// emitter samples skip those points and bring the light of the others only.
layout(constant_id = 10) const bool OFF_SCREEN_EMITTERS_ONLY = false;
// Draw part of the environment's samples from the map's luminance (binding 16), combined by
// MIS with the lobe samples; only with ENVIRONMENT_MAP.
layout(constant_id = 11) const bool ENV_SAMPLING = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform usampler2DArray voxels;
layout(set = 0, binding = 4, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 5) uniform sampler2D direct;
layout(set = 0, binding = 8, rgba32f) uniform writeonly image2D radiance;
layout(set = 0, binding = 9) uniform sampler2D gb_specular;  // albedo when !HAS_PHONG
layout(set = 0, binding = 10) uniform sampler2D gb_albedo;
layout(set = 0, binding = 15) uniform sampler2D environment_map;  // albedo unless a map
#include "environment.glsl"
#define ENV_CDF_BINDING 16
#include "environment_sampling.glsl"

// K, `shadow.direct_samples`, in the push constants' ray count.
#define SAMPLES max(gi.rays, 1u)

uvec4 vx_column(uint level, int x, int y, uint layer) {
    return texelFetch(voxels, ivec3(x, y, int(layer)), int(level));
}
uvec4 vx_ray_mask(uint a, uint b) { return ray_masks[b * 128u + a]; }
bool vx_voxel(int x, int y, int k) {
    uvec4 c = vx_column(0u, x, y, uint(k) / 128u);
    uint bit = uint(k) % 128u;
    return ((c[bit / 32u] >> (bit % 32u)) & 1u) != 0u;
}

#include "voxel_traverse.glsl"
#include "gbuffer_lobe.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"
// Whether the camera sees emitter point y (lit side's normal nl) in this frame, so that
// screen-space GI gathers its light: y lies in the frame, the camera is on its lit side, and
// the G-buffer's surface at y's pixel is y itself, within the pixel's footprint (a few
// percent of the distance) plus a voxel diagonal (the emitter's own depth precision).
bool seen_by_camera(vec3 y, vec3 nl) {
    if (!OFF_SCREEN_EMITTERS_ONLY) return false;
    vec3 to_camera = frame.camera_position.xyz - y;
    if (dot(to_camera, nl) <= 0.0) return false;
    vec4 c = frame.view_proj * vec4(y, 1.0);
    if (c.w <= 0.0) return false;
    vec2 uv = c.xy / c.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) return false;
    vec2 size = vec2(frame.counts.zw);
    ivec2 q = ivec2(uv * size);
    float depth = texelFetch(gb_depth, q, 0).r;
    if (depth >= 1.0) return false;
    vec3 seen = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, q, size, depth);
    return distance(seen, y) < 0.05 * length(to_camera) + gi.voxel_diagonal_m;
}
#define EMITTER_POINT_SKIPPED seen_by_camera
#define EMITTERS_BINDING 14
#include "emitters.glsl"

// The pixel's material with its diffuse color (gb_albedo: Lambert albedo, Phong rho_d, GGX
// (1 - m) b); the lobe target's encoding as gi_pathtrace's pixel_lobe reads it.
Lobe pixel_lobe(ivec2 px, vec3 albedo, float normal_w) {
    if (!HAS_PHONG) return lambert_lobe(albedo);
    vec4 t = texelFetch(gb_specular, px, 0);
    if (t.a > 1.5) return Lobe(LOBE_GGX, albedo, t.rgb, normal_w);
    vec3 specular = gbuffer_phong_specular(gb_specular, px);
    if (is_phong_pixel(specular)) return Lobe(LOBE_PHONG, albedo, specular, normal_w);
    return lambert_lobe(albedo);
}

// The environment's radiance along unit d from o (on a surface of normal n): the GI rays'
// start offsets (k2 along the ray, clamped; Thiedemann 2010 §5.3.1), then the environment if
// the ray leaves the grid unblocked within its length.
vec3 environment_seen(vec3 o, vec3 n, vec3 d) {
    float along = min(gi.ray_offset_voxels * gi.voxel_diagonal_m / max(dot(d, n), 1e-4),
        gi.ray_offset_max_voxels * gi.voxel_diagonal_m);
    vec3 start = o + d * along;
    vec3 ov = (gi.world_to_voxel * vec4(start, 1.0)).xyz;
    vec3 dv = mat3(gi.world_to_voxel) * d;
    float t_max = max(gi.radius_m - along, 0.0);
    VxHit h = voxel_first_hit(gi.dims, uint(gi.max_level), ov, dv, t_max, gi.start_level, gi.max_iterations);
    if (h.hit) return vec3(0.0);
    return environment_after_miss(gi.dims, ov, dv, t_max, h.ran_out, d);
}

// The i-th of `count` stratified points of the pixel (Hammersley), rotated per pixel; `salt`
// gives the emitter and the environment samples rotations of their own.
vec2 pixel_sample(uvec2 px, uint i, uint count, uint salt) {
    vec2 u = vec2((float(i) + 0.5) / float(count), radical_inverse(i));
    vec2 rot = ADVANCE ? fract(pixel_rotation(px, salt) + r2(gi.seed)) : pixel_rotation(px, gi.seed + salt);
    return fract(u + rot);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    vec4 lo = texelFetch(direct, px, 0);
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(radiance, px, lo);
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec4 ns = texelFetch(gb_normal, px, 0);
    vec3 n = normalize(ns.xyz);
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, p);
    Lobe m = pixel_lobe(px, texelFetch(gb_albedo, px, 0).rgb, ns.w);
    // The rays leave k1 voxel diagonals off the surface along its normal, as the GI rays do;
    // the light samples' geometry is the surface point's (an origin δ nearer an emitter close
    // by measured its light as if the surface were δ nearer: +19% at 1 m for δ = 0.11 m).
    vec3 o = p + n * (gi.normal_offset_voxels * gi.voxel_diagonal_m);
    vec3 sum = vec3(0.0);
    if (HAS_EMITTERS) {
        // Lambert pixels: K light samples of the whole BRDF. Phong and GGX pixels: the
        // specular part of the same K samples combined by MIS with K/2 samples of the
        // specular lobe (emitter_lobe_hit): a narrow lobe toward a small area sample alone
        // makes fireflies (cornell_pbr's metal block: relMSE 174 without GI before).
        uint lobe_count = m.kind != LOBE_LAMBERT ? max(SAMPLES / 2u, 1u) : 0u;
        float ps = float(lobe_count) / float(SAMPLES);
        uint parts = lobe_count > 0u ? 4u : 3u;
        vec3 e = vec3(0.0);
        for (uint s = 0u; s < SAMPLES; ++s) {
            e += emitter_sample_from(p, o, n, wo, m, parts, ps, pixel_sample(uvec2(px), s, SAMPLES, 0x10000u));
        }
        sum += e / float(SAMPLES);
        vec3 b = vec3(0.0);
        for (uint s = 0u; s < lobe_count; ++s) {
            vec3 w;
            vec3 d = sample_lobe(m, n, wo, true, pixel_sample(uvec2(px), s, lobe_count, 0x40000u), w);
            b += emitter_lobe_hit(o, n, wo, m, d, w, ps);
        }
        if (lobe_count > 0u) sum += b / float(lobe_count);
    }
    if (ENVIRONMENT != ENVIRONMENT_NONE) {
        // The map's own samples (ENV_SAMPLING), then the lobe's: Phong and GGX pixels at least
        // one sample of each half.
        bool env_sampling = ENV_SAMPLING && ENVIRONMENT == ENVIRONMENT_MAP;
        uint env_count = env_sampling ? uint(env_map_share() * float(SAMPLES) + 0.5) : 0u;
        uint bsdf_count = max(SAMPLES - min(env_count, SAMPLES), 1u);
        uint lobe_count = m.kind != LOBE_LAMBERT ? max(bsdf_count / 2u, 1u) : 0u;
        uint diffuse_count = max(bsdf_count - min(lobe_count, bsdf_count), 1u);
        float ne = float(env_count);
        vec3 diffuse = vec3(0.0);
        for (uint s = 0u; s < diffuse_count; ++s) {
            vec3 w;
            vec3 d = sample_lobe(m, n, wo, false, pixel_sample(uvec2(px), s, diffuse_count, 0x20000u), w);
            if (dot(d, n) <= 0.0) continue;
            if (env_sampling) {
                w *= env_balance(float(diffuse_count) * lobe_pdf(m, n, wo, d, false), ne * env_pdf(d));
            }
            diffuse += w * environment_seen(o, n, d);
        }
        sum += m.diffuse * diffuse / float(diffuse_count);
        vec3 lobe = vec3(0.0);
        for (uint s = 0u; s < lobe_count; ++s) {
            vec3 w;
            vec3 d = sample_lobe(m, n, wo, true, pixel_sample(uvec2(px), s, lobe_count, 0x30000u), w);
            if (dot(d, n) <= 0.0) continue;
            if (env_sampling) {
                w *= env_balance(float(lobe_count) * lobe_pdf(m, n, wo, d, true), ne * env_pdf(d));
            }
            lobe += w * environment_seen(o, n, d);
        }
        if (lobe_count > 0u) sum += lobe / float(lobe_count);
        // Each map sample: f_d L cos / (n_d p_d + K_e p_e) + f_s L cos / (n_s p_s + K_e p_e),
        // already divided by its count through the balance heuristic's denominators.
        for (uint s = 0u; s < env_count; ++s) {
            float pe;
            vec3 d = env_sample(pixel_sample(uvec2(px), s, env_count, 0x50000u), pe);
            float ci = dot(d, n);
            if (ci <= 0.0 || pe <= 0.0) continue;
            vec3 f = lobe_part_brdf(m, n, d, wo, false) / (float(diffuse_count) * lobe_pdf(m, n, wo, d, false) + ne * pe);
            if (lobe_count > 0u) {
                f += lobe_part_brdf(m, n, d, wo, true) / (float(lobe_count) * lobe_pdf(m, n, wo, d, true) + ne * pe);
            }
            if (all(equal(f, vec3(0.0)))) continue;
            sum += f * ci * environment_seen(o, n, d);
        }
    }
    imageStore(radiance, px, vec4(lo.rgb + sum, lo.a));
}

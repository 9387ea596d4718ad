#version 450
// The voxel path tracer (Thiedemann 2010, §6.4.2): from each G-buffer point, `rays` paths of B bounces
// (or unbounded, see below) through the binary voxel hierarchy; at every hit the albedo, normal
// and (with HAS_MATERIAL_VOLUME) the Phong or GGX lobe come from the volumes congruent with the
// bits and the direct light there from the shadow maps (next event estimation), so each bounce
// adds throughput * f * E_direct. Every bounce samples its surface's lobes with
// material_lobe.glsl's sample_lobe: the first one splits the pixel's paths half diffuse, half
// specular lobe (stratified); a later one picks the specular lobe with
// lobe_specular_probability and divides by it. Cosine sampling of Lambert bounces makes the
// throughput factor the albedo. Without the material volume later bounces are Lambert with the
// albedo volume's color (GGX: the base color). Every ray starts k1 voxel diagonals off its
// surface along the normal and k2 h / (d . n) (clamped) along the ray (Thiedemann 2010 §5.3.1). Samples: Hammersley for the first
// bounce, Halton (2,3) and (5,7) for the next two, hashed random after, all rotated per pixel
// and per accumulated frame. The irradiance estimate E = pi/N sum L is accumulated over frames
// into a history image while camera and scene stay still. A path whose ray leaves the voxel
// grid within its radius ends there with the environment's radiance (ENVIRONMENT,
// environment.glsl; see escaped_radiance): a sky-lit point gets its sky light by cosine or
// lobe sampling. With ENV_SAMPLING (`gi.env_sampling`, a map) every path vertex that samples
// a further bounce also draws, with probability c = min(2 alpha, 1) (alpha the map's share,
// environment_sampling.glsl's env_map_share: 1/2 for a sun, so c = 1; 0 for a smooth sky),
// one direction from the map's luminance and traces it like a BSDF ray; the two are
// combined by the balance heuristic with c the map's expected count, per lobe part as the
// emitters' samples are: the map sample weighs f_part L cos / (p_part + c p_e) for each part
// the vertex samples (p_part including the lobe choice's probability), and a BSDF ray that
// escapes weighs p_bsdf / (p_bsdf + c p_e). The two weights' expectations sum to 1 wherever
// either density is positive (c p_e / (p_part + c p_e) + p_part / (p_part + c p_e)), so the
// estimate stays unbiased for any c; c = 1 is Veach's (1997, §9.2.2) balance heuristic with
// one sample of each, and c spends the map's rays only where alpha says they pay.
//
// With HAS_EMITTERS (emissive triangles and `gi.emitter_sampling`) every path vertex that
// samples a further bounce also samples one emissive triangle by power (emitters.glsl): the
// light sample and the BSDF ray's emitter hit are weighted by the power heuristic, each half
// of the first bounce's split with its own part of the lobe, later vertices with both parts
// and the lobe choice's probability in the BSDF density.
//
// Unbounded paths (bounces 0 in the push constants) take ROULETTE_AFTER bounces, then Russian
// roulette (Arvo and Kirk 1990): before each further bounce the path goes on with probability
// q = min(max throughput component, 0.95) and divides its throughput by q, so every bounce's
// expected contribution is that of the untruncated path and the estimate is unbiased. The
// 0.95 keeps paths finite even at albedo 1 (each further bounce survives with at most 0.95).
// MAX_PATH_BOUNCES is a safety cap on the loop, and the only bias: the expectation becomes the
// sum of the first 64 bounces. Bounce k carries a throughput of at most a_max^k (a_max the
// largest albedo), so the dropped tail is at most a_max^65 / (1 - a_max) times the largest
// direct radiance at a hit; in a closed furnace of albedo a it is exactly the fraction a^65 of
// the result: 1.3e-9 for the Cornell box's white (0.73), 3.6e-2 at a = 0.95 (the q clamp does
// not enter: it sets the variance, not the expectation).
#include "frame.glsl"
#include "gi_common.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;  // the G-buffer has a lobe target (Phong or GGX)
layout(constant_id = 1) const bool HAS_EMISSION = false;
layout(constant_id = 2) const bool HAS_MATERIAL_VOLUME = false;  // lobes at later bounces
layout(constant_id = 3) const bool HAS_EMITTERS = false;  // next-event estimation (binding 14)
layout(constant_id = 8) const uint ENVIRONMENT = 0u;  // environment.glsl's kinds
// Off under temporal accumulation (gi_temporal.comp accumulates, with reprojection): the
// output is this frame's estimate alone, and the seed is the frame's sample index.
layout(constant_id = 9) const bool ACCUMULATE = true;
// Next-event estimation toward the environment map (binding 16); only with ENVIRONMENT_MAP.
layout(constant_id = 11) const bool ENV_SAMPLING = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform usampler2DArray voxels;
layout(set = 0, binding = 4, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 5) uniform sampler3D albedo_volume;
layout(set = 0, binding = 6) uniform sampler3D normal_volume;
layout(set = 0, binding = 7) uniform sampler2DArray shadow_maps;
layout(set = 0, binding = 8, rgba32f) uniform image2D history;
layout(set = 0, binding = 9) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 10) uniform sampler2D gb_albedo;
layout(set = 0, binding = 12) uniform sampler3D emission_volume;  // albedo when !HAS_EMISSION
layout(set = 0, binding = 13) uniform sampler3D material_volume;  // albedo when !HAS_MATERIAL_VOLUME
layout(set = 0, binding = 15) uniform sampler2D environment_map;  // albedo unless a map
#include "environment.glsl"
#define ENV_CDF_BINDING 16
#include "environment_sampling.glsl"

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
#include "shadow.glsl"
#include "gbuffer_lobe.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"
#define EMITTERS_BINDING 14
#include "emitters.glsl"
#include "voxel_path.glsl"

// The light sample of path `path` at vertex `bounce`: at the pixel the rays' Hammersley points
// under a rotation of their own (stratified over the pixel's paths like the first bounce),
// later hashed like the roulette numbers, with another constant so the two differ.
vec2 emitter_sample_u(uvec2 px, uint bounce, uint s, uint rays, uint path, uint frame_index) {
    if (bounce == 0u) {
        vec2 u = vec2((float(s) + 0.5) / float(rays), radical_inverse(s));
        return fract(u + pixel_rotation(px, frame_index + 0x10000u));
    }
    uint h = wang_hash(px.x * 1973u + px.y * 9277u);
    h = wang_hash(h ^ (path * 0x9e3779b9u));
    h = wang_hash(h + bounce * 0x85ebca6bu + 0x68e31da4u);
    uint h2 = wang_hash(h ^ 0x5bd1e995u);
    return vec2(float(h >> 8u), float(h2 >> 8u)) * (1.0 / 16777216.0);
}

// The environment map's sample of path `path` at vertex `bounce`: emitter_sample_u's scheme
// under other constants, so the two strategies' points are not correlated.
vec2 env_sample_u(uvec2 px, uint bounce, uint s, uint rays, uint path, uint frame_index) {
    if (bounce == 0u) {
        vec2 u = vec2((float(s) + 0.5) / float(rays), radical_inverse(s));
        return fract(u + pixel_rotation(px, frame_index + 0x20000u));
    }
    uint h = wang_hash(px.x * 1973u + px.y * 9277u);
    h = wang_hash(h ^ (path * 0x9e3779b9u));
    h = wang_hash(h + bounce * 0x85ebca6bu + 0x2545f491u);
    uint h2 = wang_hash(h ^ 0x27d4eb2fu);
    return vec2(float(h >> 8u), float(h2 >> 8u)) * (1.0 / 16777216.0);
}

// The material at a voxel hit: the material volume's lobe, or Lambert with the albedo.
Lobe hit_lobe(ivec3 v, vec3 albedo) {
    return HAS_MATERIAL_VOLUME ? voxel_lobe(albedo, texelFetch(material_volume, v, 0)) : lambert_lobe(albedo);
}

// The G-buffer pixel's material (the diffuse color is applied after the paths, see main).
// Lobe kinds of the lobe target: 1 Phong (rho_s, exponent in the normal's w), 2 GGX (F0,
// roughness in the normal's w).
Lobe pixel_lobe(ivec2 px, float normal_w) {
    if (!HAS_PHONG) return lambert_lobe(vec3(1.0));
    vec4 t = texelFetch(gb_specular, px, 0);
    if (t.a > 1.5) return Lobe(LOBE_GGX, vec3(1.0), t.rgb, normal_w);
    vec3 specular = gbuffer_phong_specular(gb_specular, px);
    if (is_phong_pixel(specular)) return Lobe(LOBE_PHONG, vec3(1.0), specular, normal_w);
    return lambert_lobe(vec3(1.0));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    uint frame_index = gi.seed;
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(history, px, vec4(0.0));
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec4 ns = texelFetch(gb_normal, px, 0);
    vec3 n = normalize(ns.xyz);
    Lobe pixel = pixel_lobe(px, ns.w);
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, p);
    // Phong and GGX pixels spend half their paths on the specular lobe (first bounce).
    uint lobe_rays = pixel.kind != LOBE_LAMBERT ? max(gi.rays, 1u) / 2u : 0u;
    float offset = gi.normal_offset_voxels * gi.voxel_diagonal_m;
    uint rays = max(gi.rays, 1u);
    uint bounce_param = gi.bounces;
    bool roulette = bounce_param == 0u;
    uint bounces = roulette ? MAX_PATH_BOUNCES : bounce_param;
    vec2 rot = pixel_rotation(uvec2(px), frame_index);
    uint diffuse_rays = rays - lobe_rays;
    vec3 sum = vec3(0.0);
    vec3 lobe_sum = vec3(0.0);
    for (uint s = 0u; s < rays; ++s) {
        bool lobe = s >= diffuse_rays;
        uint j = lobe ? s - diffuse_rays : s;
        uint count = lobe ? lobe_rays : diffuse_rays;
        vec3 o = p + n * offset;
        // Where the vertex's surface is: the light samples' geometry is taken there, their
        // visibility from o (off the surface's own voxels).
        vec3 g = p;
        vec3 nn = n;
        vec3 from = wo;
        Lobe m = pixel;
        vec3 throughput = vec3(1.0);
        vec3 l = vec3(0.0);
        for (uint b = 0u; b < bounces; ++b) {
            vec2 u = bounce_sample(b, j, count, frame_index, rot);
            // The first bounce takes the stratified split; a later one picks a lobe at random,
            // reusing u.x (rescaled) as the choice.
            bool specular = lobe;
            float pick = 1.0;
            if (b > 0u) {
                float ps = lobe_specular_probability(m);
                specular = u.x < ps;
                u.x = specular ? u.x / ps : (u.x - ps) / (1.0 - ps);
                pick = specular ? ps : 1.0 - ps;
            }
            // The light sample at this vertex, before the BSDF ray leaves it.
            if (HAS_EMITTERS) {
                uint parts = b == 0u ? (lobe ? 1u : 0u) : 2u;
                float ps = b == 0u ? 0.0 : lobe_specular_probability(m);
                vec2 ul = emitter_sample_u(uvec2(px), b, j, count, frame_index * rays + s, frame_index);
                l += throughput * emitter_sample_from(g, o, nn, from, m, parts, ps, ul);
            }
            // The environment map's sample at this vertex: one direction by luminance, the
            // parts of the lobe this vertex samples (as the emitter sample's `parts`), each
            // weighted against its own BSDF density.
            bool env_sampling = ENV_SAMPLING && ENVIRONMENT == ENVIRONMENT_MAP;
            // The map sample's expected count c; its first coordinate decides whether this
            // vertex draws one (u.x < c) and, rescaled, places it.
            float env_c = env_sampling ? min(2.0 * env_map_share(), 1.0) : 0.0;
            vec2 ue = env_sampling ? env_sample_u(uvec2(px), b, j, count, frame_index * rays + s, frame_index) : vec2(1.0);
            if (env_sampling && ue.x < env_c) {
                float pe;
                ue.x = min(ue.x / env_c, 1.0);
                vec3 de = env_sample(ue, pe);
                float ci = dot(de, nn);
                if (ci > 0.0 && pe > 0.0) {
                    float ps = b == 0u ? (lobe ? 1.0 : 0.0) : lobe_specular_probability(m);
                    vec3 f = vec3(0.0);
                    if (ps < 1.0) {
                        f += lobe_part_brdf(m, nn, de, from, false) / ((1.0 - ps) * lobe_pdf(m, nn, from, de, false) + env_c * pe);
                    }
                    if (ps > 0.0) {
                        f += lobe_part_brdf(m, nn, de, from, true) / (ps * lobe_pdf(m, nn, from, de, true) + env_c * pe);
                    }
                    if (any(greaterThan(f, vec3(0.0)))) {
                        vec3 estart;
                        VxHit eh = trace_from(o, nn, de, estart);
                        if (!eh.hit) l += throughput * f * ci * escaped_radiance(o, estart, de, eh);
                    }
                }
            }
            vec3 w;
            vec3 d = sample_lobe(m, nn, from, specular, u, w);
            if (dot(d, nn) <= 0.0) break;  // a lobe sample below the surface
            // The BSDF ray's density, for the weight of an emitter or the map it hits.
            float pdf_bsdf = HAS_EMITTERS || env_sampling ? pick * lobe_pdf(m, nn, from, d, specular) : 0.0;
            // The diffuse color of the first bounce is applied after the paths.
            if (b > 0u && !specular) w *= m.diffuse;
            throughput *= w / pick;
            if (roulette && b >= ROULETTE_AFTER) {
                float q = min(max(throughput.r, max(throughput.g, throughput.b)), 0.95);
                if (roulette_sample(uvec2(px), frame_index * rays + s, b) >= q) break;
                throughput /= q;
            }
            vec3 start;
            VxHit h = trace_from(o, nn, d, start);
            if (!h.hit) {
                if (ENVIRONMENT != ENVIRONMENT_NONE) {
                    float weight = env_sampling ? env_balance(pdf_bsdf, env_c * env_pdf(d)) : 1.0;
                    l += throughput * (weight * escaped_radiance(o, start, d, h));
                }
                break;
            }
            ivec3 v = ivec3(h.voxel);
            vec3 a = texelFetch(albedo_volume, v, 0).rgb;
            vec4 nd = texelFetch(normal_volume, v, 0);
            vec3 hn = nd.xyz;
            hn = dot(hn, hn) > 0.25 ? normalize(hn) : -d;
            bool back = dot(hn, d) > 0.0;
            if (back) hn = -hn;  // the side the ray arrives at
            vec3 hp = start + d * h.t;
            // An emitter sends its radiance from the side its normal points to (Mitsuba's area
            // emitter); the camera's own view of emitters is deferred_direct's.
            if (HAS_EMISSION && !back) {
                // The half-float emission volume holds pre-exposed radiance (frame.glsl).
                vec3 le = texelFetch(emission_volume, v, 0).rgb * frame.radiance_scale.y;
                if (HAS_EMITTERS) le *= emitter_hit_weight(le, length(hp - o), -dot(hn, d), pdf_bsdf);
                l += throughput * le;
            }
            m = hit_lobe(v, a);
            // The light at the surface inside the hit voxel, not at the ray's entry into it.
            vec3 hs = voxel_surface_point(gi.world_to_voxel, v, nd, start, d, h.t);
            l += throughput * direct_at(hs, hn, -d, m);
            // The next bounce starts a voxel diagonal (k1, at most the way it came) back along
            // the ray, not off the hit voxel along its normal: hp is where the ray entered the
            // hit voxel, and the voxel's normal may belong to a surface behind a wall thinner
            // than a voxel, through which the normal offset would push the origin. Every
            // point the ray passed through empty voxels is on its own side (`voxgi bench leak`).
            o = hp - d * min(offset, h.t);
            g = hs;
            nn = hn;
            from = -d;
        }
        if (lobe) lobe_sum += l;
        else sum += l;
    }
    // Lambert pixels: the irradiance E = pi mean(L). Phong and GGX pixels: their indirect
    // radiance, diffuse/pi * E (E with the GGX diffuse weights) plus the lobe estimate.
    vec3 e = sum * (PI / float(max(diffuse_rays, 1u)));
    if (pixel.kind != LOBE_LAMBERT) {
        vec3 diffuse = texelFetch(gb_albedo, px, 0).rgb;
        e = diffuse / PI * e + lobe_sum / float(max(lobe_rays, 1u));
    }
    if (!ACCUMULATE) {
        imageStore(history, px, vec4(e, 1.0));
        return;
    }
    vec3 old = frame_index == 0u ? e : imageLoad(history, px).rgb;
    imageStore(history, px, vec4(mix(old, e, 1.0 / float(frame_index + 1u)), 1.0));
}

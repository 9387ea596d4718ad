// The voxel path tracer's building blocks (gi_pathtrace.comp; Thiedemann 2010 §6.4.2), shared
// with oit_gather_indirect.frag, which traces the same paths from transparent fragments: direct
// light at a path vertex from the shadow maps, the roulette numbers, the bounce samples, the
// offset first-hit test and the environment's radiance where a path leaves the grid.
//
// The including shader declares, before including this file: the frame buffer `frame`, the
// GI parameters `gi` (gi_common.glsl's block or a buffer of the same members), the shadow maps
// `shadow_maps`, the constant ENVIRONMENT and the sampler `environment_map`, and includes
// gi_common.glsl, voxel_traverse.glsl, shadow.glsl, material_lobe.glsl and environment.glsl.
#ifndef VOXEL_PATH_GLSL
#define VOXEL_PATH_GLSL
// Outgoing radiance toward wo at p (normal n, material m) from every light, shadowed.
vec3 direct_at(vec3 p, vec3 n, vec3 wo, Lobe m) {
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
        lo += lobe_brdf(m, n, wi, wo) * e * shadow_visibility(shadow_maps, l, p, n, max(dot(n, wi), 0.0));
    }
    return lo;
}

const uint ROULETTE_AFTER = 3u;     // Bounces::ROULETTE_AFTER in src/gi/mod.rs
const uint MAX_PATH_BOUNCES = 64u;  // Bounces::MAX

// The roulette number of path `path` (frame_index * rays + s) before bounce `bounce` at pixel
// px: the pixel's hash chained with the path and the bounce (wang_hash is a bijection, so the
// paths of a pixel get distinct hash chains). Deliberately not rotated by the pixel's `rot`
// like the direction samples: every direction dimension shares that rotation, which would put
// the roulette number a fixed offset from a direction coordinate of the same path.
float roulette_sample(uvec2 px, uint path, uint bounce) {
    uint h = wang_hash(px.x * 1973u + px.y * 9277u);
    h = wang_hash(h ^ (path * 0x9e3779b9u));
    h = wang_hash(h + bounce * 0x85ebca6bu);
    // 24 bits: P(u < q) differs from q by less than 6e-8.
    return float(h >> 8u) * (1.0 / 16777216.0);
}

float halton(uint i, uint base) {
    float f = 1.0, r = 0.0;
    while (i > 0u) {
        f /= float(base);
        r += f * float(i % base);
        i /= base;
    }
    return r;
}

vec2 bounce_sample(uint bounce, uint s, uint rays, uint frame_index, vec2 rot) {
    uint i = frame_index * rays + s;
    vec2 u;
    if (bounce == 0u) u = vec2((float(s) + 0.5) / float(rays), radical_inverse(s));
    else if (bounce == 1u) u = vec2(halton(i + 1u, 2u), halton(i + 1u, 3u));
    else if (bounce == 2u) u = vec2(halton(i + 1u, 5u), halton(i + 1u, 7u));
    else u = pixel_rotation(uvec2(i, bounce), frame_index * 31u + s);
    return fract(u + rot);
}

// The first hit of a ray from o (on a surface of normal n) along d, offset k2 h / (d . n)
// along the ray, clamped (Thiedemann 2010 §5.3.1, as the hemisphere rays do), so grazing rays
// leave their surface's own voxels too; returns the hit and in `start` the offset origin.
VxHit trace_from(vec3 o, vec3 n, vec3 d, out vec3 start) {
    float along = min(gi.ray_offset_voxels * gi.voxel_diagonal_m / max(dot(d, n), 1e-4),
        gi.ray_offset_max_voxels * gi.voxel_diagonal_m);
    start = o + d * along;
    vec3 ov = (gi.world_to_voxel * vec4(start, 1.0)).xyz;
    return voxel_first_hit(gi.dims, uint(gi.max_level), ov, mat3(gi.world_to_voxel) * d,
        max(gi.radius_m - along, 0.0), gi.start_level, gi.max_iterations);
}

// The radiance a ray from o that trace_from started at `start` along d brings back when it hit
// nothing (h): the environment's, if it left the grid within its length (environment.glsl).
vec3 escaped_radiance(vec3 o, vec3 start, vec3 d, VxHit h) {
    float t_max = max(gi.radius_m - distance(start, o), 0.0);
    vec3 ov = (gi.world_to_voxel * vec4(start, 1.0)).xyz;
    return environment_after_miss(gi.dims, ov, mat3(gi.world_to_voxel) * d, t_max, h.ran_out, d);
}

#endif

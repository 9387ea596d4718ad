// Body of gi_hemisphere.comp (radiance at hits from the reflective light maps),
// gi_hemisphere_emission.comp (the same plus emitters from the emission volume,
// EMISSION_FROM_VOLUME) and gi_hemisphere_volume.comp (from the direct-radiance voxel volume,
// RADIANCE_FROM_VOLUME).
// Indirect light by hemisphere sampling (Thiedemann 2010, §6.2, §6.4.1): from each G-buffer point, N
// cosine-distributed rays (Hammersley points with a per-pixel Cranley-Patterson rotation)
// are cast through the binary voxel hierarchy within a radius; at a hit, the radiance the
// lights put there is read from the reflective light maps (§6.3.3), valid only if the map saw
// the same surface (distance tolerance) from the side the ray hits (back-face test). With
// cosine sampling the irradiance estimate is E = pi/N * sum L. Glossy receivers sample their
// lobe too (§5.7 for Phong): Phong and GGX pixels spend half their rays on the specular lobe
// (GGX metals all of them) and store their indirect radiance, the diffuse part's estimate plus
// the lobe's; a GGX pixel's rays are material_lobe.glsl's, as the path tracer's first bounce.
// A ray that leaves the voxel grid within its radius reads the environment (ENVIRONMENT,
// environment.glsl): the sky's light at the pixel, with voxel visibility.
#include "frame.glsl"
#include "gi_common.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;
// Some material is GGX: light-map senders that are GGX send their whole BRDF toward the ray.
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 8) const uint ENVIRONMENT = 0u;  // environment.glsl's kinds
// Temporal accumulation (gi_temporal.comp): the per-pixel rotation of the ray pattern advances
// by the R2 sequence of the frame (gi.seed, counted per frame), so that the frames' patterns
// interleave and N frames of K rays cover the hemisphere like N·K rays.
layout(constant_id = 9) const bool ADVANCE = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform usampler2DArray voxels;
layout(set = 0, binding = 4, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
#ifdef RADIANCE_FROM_VOLUME
layout(set = 0, binding = 5) uniform sampler3D radiance_volume;  // rgb radiance, a: lit side
layout(set = 0, binding = 6) uniform sampler3D normal_volume;
// Glossy senders (HAS_PHONG or HAS_GGX): a hit voxel's material, base color and emission, to
// add its specular lobe toward the ray (read only then; otherwise the albedo volume fills the
// material and emission bindings).
layout(constant_id = 2) const bool HAS_EMISSION = false;
layout(set = 0, binding = 7) uniform sampler3D material_volume;
layout(set = 0, binding = 11) uniform sampler3D albedo_volume;
layout(set = 0, binding = 13) uniform sampler3D emission_volume;
#else
layout(set = 0, binding = 5) uniform sampler2DArray rlm_radiance;
layout(set = 0, binding = 6) uniform sampler2DArray rlm_position;
layout(set = 0, binding = 7) uniform sampler2DArray rlm_normal;
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 11, std430) readonly buffer Materials { GpuMaterial materials[]; };
// GGX parameters per material (gbuffer.frag's table; read only when HAS_GGX).
struct GpuMaterialPbr { vec4 ggx; vec4 emission; uvec4 maps; };
layout(set = 0, binding = 14, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };
#ifdef EMISSION_FROM_VOLUME
layout(set = 0, binding = 12) uniform sampler3D emission_volume;
layout(set = 0, binding = 13) uniform sampler3D normal_volume;
#endif
#endif
layout(set = 0, binding = 8, rgba32f) uniform writeonly image2D irradiance;
layout(set = 0, binding = 9) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 10) uniform sampler2D gb_albedo;
layout(set = 0, binding = 15) uniform sampler2D environment_map;  // albedo unless a map
#include "environment.glsl"

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
#include "paraboloid.glsl"
#include "gbuffer_lobe.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"

#ifdef RADIANCE_FROM_VOLUME
#include "voxel_light.glsl"

// Radiance of the hit voxel's lit side, if the ray arrives on that side (back-face test).
// A glossy voxel (the material volume) sends its whole BRDF toward the ray, wo = -dir, as a
// light-map texel does: the volume holds its diffuse part (GGX: times (1 - F_d(n.wi)), so the
// lookup multiplies (1 - F_d(n.wo)) in, leaving the emission out), and the specular lobe
// f_s(wi, wo) E V is evaluated here per light, with E exactly as gi_radiance_volume.comp
// computes it, at the voxel's center on the side the ray arrives on (voxel_light.glsl), and V
// the visibility that pass kept in the volume's a (|a| = 1 + V): the light's own with one
// light, the lights' irradiance-weighted mean with several. No shadow lookup here: on
// lavapipe, which executes every branch for all lanes, a PCF lookup per light made every hit
// of a glossy scene pay for it (the pass took 1.8 times as long). Normal and material are the
// voxel's averages.
vec3 hit_radiance(VxHit h, vec3 hit, vec3 dir) {
    vec4 r = texelFetch(radiance_volume, ivec3(h.voxel), 0);
    vec3 n = texelFetch(normal_volume, ivec3(h.voxel), 0).xyz * (r.a < 0.0 ? -1.0 : 1.0);
    bool on_lit_side = dot(n, -dir) > 0.0;
    vec3 lit = on_lit_side ? r.rgb : vec3(0.0);
    if (!(HAS_PHONG || HAS_GGX)) return lit;
    ivec3 v = ivec3(h.voxel);
    vec4 t = texelFetch(material_volume, v, 0);
    if (t.w == 0.0) return lit;  // Lambert
    Lobe m = voxel_lobe(texelFetch(albedo_volume, v, 0).rgb, t);
    vec3 wo = -dir;
    vec3 nv = texelFetch(normal_volume, v, 0).xyz;
    nv = dot(nv, nv) > 0.25 ? normalize(nv) : vec3(0.0, 1.0, 0.0);
    vec3 ns = dot(nv, wo) >= 0.0 ? nv : -nv;
    if (m.kind == LOBE_GGX) {
        // Emission is added to the front side only (gi_radiance_volume.comp).
        // The half-float emission volume holds pre-exposed radiance (frame.glsl).
        vec3 em = HAS_EMISSION && on_lit_side && r.a > 0.0
            ? texelFetch(emission_volume, v, 0).rgb * frame.radiance_scale.y : vec3(0.0);
        lit = (lit - em) * ggx_diffuse_weight(dot(ns, wo)) + em;
    }
    vec3 p = (inverse(gi.world_to_voxel) * vec4(vec3(v) + 0.5, 1.0)).xyz;
    vec3 lobe = vec3(0.0);
    for (uint i = 0u; i < frame.counts.x; ++i) {
        vec3 wi;
        vec3 e = voxel_light_e(frame.lights[i], p, ns, wi);
        // Roughness kept at r >= 0.01 (alpha >= 1e-4), where D stays finite (as the light maps).
        vec3 f = m.kind == LOBE_GGX ? brdf_ggx_specular(m.specular, max(m.param, 0.01), ns, wi, wo)
                                    : brdf_phong(m.specular, m.param, ns, wi, wo);
        lobe += f * e;
    }
    lit += lobe * (abs(r.a) - 1.0);
    return lit;
}
#else
// Radiance leaving the surface at world point `hit`, seen along `dir`, from every light's
// reflective map that saw that surface.
vec3 light_map_radiance(vec3 hit, vec3 dir) {
    vec3 sum = vec3(0.0);
    ivec2 size = textureSize(rlm_radiance, 0).xy;
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight l = frame.lights[i];
        if (l.info.z == 0u) continue;
        uint v = shadow_view_index(l, hit);
        GpuShadowView sv = frame.shadow_views[v];
        vec4 c = sv.view_proj * vec4(hit, 1.0);
        vec2 map_xy;
        float texel_m;
        if (sv.params.y > 1.5) {
            // A paraboloid view (an area-light element's hemisphere; paraboloid.glsl): the
            // hit's direction from the light, within the hemisphere and its radial range.
            float r = length(c.xyz);
            if (c.z < 0.0 || r > sv.params.w) continue;
            map_xy = paraboloid_uv(c.xyz);
            texel_m = paraboloid_texel_m(sv, hit) * gi.light_map_scale;
        } else {
            if (c.w <= 0.0) continue;
            vec3 ndc = c.xyz / c.w;
            if (any(greaterThan(abs(ndc.xy), vec2(1.0))) || ndc.z < 0.0 || ndc.z > 1.0) continue;
            map_xy = ndc.xy;
            texel_m = sv.params.x * gi.light_map_scale * (sv.params.y > 0.5 ? 1.0 : c.w);
        }
        ivec2 q = clamp(ivec2(floor((map_xy * 0.5 + 0.5) * vec2(size))), ivec2(0), size - 1);
        vec4 pos = texelFetch(rlm_position, ivec3(q, int(v)), 0);
        if (pos.w == 0.0) continue;  // the light sees nothing there
        vec3 n = texelFetch(rlm_normal, ivec3(q, int(v)), 0).xyz;
        // Direction from the stored surface point to the light.
        vec3 wl = l.info.x == LIGHT_DIRECTIONAL ? -l.direction.xyz : normalize(l.position.xyz - pos.xyz);
        float cos_l = max(dot(n, wl), 0.0);
        // Tolerance (§6.3.3): the hit lies on the boundary of the hit voxel (up to a diagonal
        // from the surface) plus the light-map texel's footprint on a surface at this slope,
        // clamped so grazing texels do not accept far points.
        float footprint = min(texel_m / max(cos_l, 0.05), 8.0 * gi.voxel_diagonal_m);
        float tol = gi.hit_tolerance_voxels * gi.voxel_diagonal_m + 2.0 * footprint;
        if (distance(pos.xyz, hit) > tol) continue;
        if (dot(n, -dir) <= 0.0) continue;  // the ray reached the back of that surface
        vec3 radiance = texelFetch(rlm_radiance, ivec3(q, int(v)), 0).rgb;
        // Glossy senders: their lobe toward the ray, f(wl, -dir) E, from the irradiance the
        // light puts there (E = I cos / d^2 with the spot falloff, or E_perp cos), recomputed
        // from the stored position and normal (the texel's view names the light, its position's
        // w the material); the map itself holds only the diffuse part.
        uint material = max(uint(pos.w + 0.5), 1u) - 1u;
        GpuMaterial m = materials[material];
        bool ggx = HAS_GGX && pbr[material].ggx.z != 0.0;
        if (ggx || (m.specular.a > 0.0 && any(greaterThan(m.specular.rgb, vec3(0.0))))) {
            vec3 e;
            if (l.info.x == LIGHT_DIRECTIONAL) {
                e = l.intensity.rgb * cos_l;
            } else {
                vec3 d = l.position.xyz - pos.xyz;
                float falloff = light_falloff(l, dot(-wl, l.direction.xyz));
                e = l.intensity.rgb * (falloff * cos_l / max(dot(d, d), 1e-30));
            }
            if (ggx) {
                // GGX (brdf.glsl's brdf_ggx): the map's (1 - m) b / pi (1 - F_d(n.wl)) E times
                // the factor (1 - F_d(n.wo)) toward the ray, plus the specular lobe with
                // F0 = mix(0.04, b, m), b the base color (the material's albedo). Roughness is
                // kept at r >= 0.01 (alpha >= 1e-4), where D stays finite.
                vec3 nn = normalize(n);
                vec4 g = pbr[material].ggx;
                vec3 f0 = mix(vec3(0.04), m.albedo.rgb, g.y);
                radiance = radiance * ggx_diffuse_weight(dot(nn, -dir))
                    + brdf_ggx_specular(f0, max(g.x, 0.01), nn, wl, -dir) * e;
            } else {
                float ca = dot(reflect(-wl, n), -dir);
                radiance += m.specular.rgb * (m.specular.a + 2.0) / (2.0 * PI)
                    * phong_cos_power(ca, m.specular.a) * e;
            }
        }
        sum += radiance;
    }
    return sum;
}

#ifdef EMISSION_FROM_VOLUME
// Emitted radiance of the hit voxel's owner, if the ray arrives on its front side (the face
// normal's side, Mitsuba's area emitter), as the path tracer adds it at a hit: the light maps
// see only what the lights see, so emitters reach other surfaces only this way.
vec3 emitted_radiance(VxHit h, vec3 dir) {
    ivec3 v = ivec3(h.voxel);
    vec3 n = texelFetch(normal_volume, v, 0).xyz;
    if (dot(n, n) > 0.25 && dot(n, dir) > 0.0) return vec3(0.0);
    return texelFetch(emission_volume, v, 0).rgb * frame.radiance_scale.y;  // pre-exposed
}
#endif

vec3 hit_radiance(VxHit h, vec3 hit, vec3 dir) {
#ifdef EMISSION_FROM_VOLUME
    return light_map_radiance(hit, dir) + emitted_radiance(h, dir);
#else
    return light_map_radiance(hit, dir);
#endif
}
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(irradiance, px, vec4(0.0));
        return;
    }
    vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, vec2(size), depth);
    vec4 ns = texelFetch(gb_normal, px, 0);
    vec3 n = normalize(ns.xyz);
    vec3 specular = HAS_PHONG ? gbuffer_phong_specular(gb_specular, px) : vec3(0.0);
    bool phong = HAS_PHONG && is_phong_pixel(specular);
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, p);
    vec3 mirror = reflect(-wo, n);
    // GGX receivers (HAS_GGX): F0 in the lobe target, the roughness in the normal's w, the
    // diffuse color (1 - m) b in the albedo (docs/ARCHITECTURE.md, "Materials").
    vec4 lobe_texel = HAS_GGX ? texelFetch(gb_specular, px, 0) : vec4(0.0);
    bool ggx = HAS_GGX && lobe_texel.a > 1.5;
    vec3 diffuse = ggx ? texelFetch(gb_albedo, px, 0).rgb : vec3(0.0);
    Lobe receiver = Lobe(LOBE_GGX, diffuse, lobe_texel.rgb, ns.w);
    // Self-intersection offset along the normal (Thiedemann 2010 §5.3.1).
    vec3 origin = p + n * (gi.normal_offset_voxels * gi.voxel_diagonal_m);
    vec3 ov = (gi.world_to_voxel * vec4(origin, 1.0)).xyz;
    mat3 dir_to_voxel = mat3(gi.world_to_voxel);
    uint rays = max(gi.rays, 1u);
    // Phong and GGX pixels spend half their rays on the specular lobe, metals (a black
    // diffuse part) all of them.
    uint lobe_rays = phong ? rays / 2u : 0u;
    if (ggx) lobe_rays = lobe_specular_probability(receiver) == 1.0 ? rays : rays / 2u;
    uint diffuse_rays = rays - lobe_rays;
    vec2 rot = ADVANCE ? fract(pixel_rotation(uvec2(px), 0u) + r2(gi.seed))
                       : pixel_rotation(uvec2(px), gi.seed);
    vec3 sum = vec3(0.0);
    vec3 lobe_sum = vec3(0.0);
    for (uint i = 0u; i < rays; ++i) {
        bool lobe = i >= diffuse_rays;
        uint j = lobe ? i - diffuse_rays : i;
        uint count = lobe ? lobe_rays : diffuse_rays;
        vec2 u = fract(vec2((float(j) + 0.5) / float(count), radical_inverse(j)) + rot);
        // GGX: visible-normal samples weighted F(wo.h) G1(wi), or cosine samples weighted
        // (1 - F_d(n.wi)) (1 - F_d(n.wo)) (material_lobe.glsl's sample_lobe).
        vec3 w = vec3(1.0);
        vec3 d = ggx ? sample_lobe(receiver, n, wo, lobe, u, w)
                     : (lobe ? phong_direction(mirror, ns.w, u) : cosine_direction(n, u));
        float cos_n = dot(d, n);
        if (cos_n <= 0.0) continue;  // a lobe sample below the surface contributes nothing
        // Offset along the ray (Thiedemann 2010 §5.3.1): k2 * h / (d . n), clamped, so grazing
        // rays leave the surface's own voxels too.
        float along = min(gi.ray_offset_voxels * gi.voxel_diagonal_m / max(dot(d, n), 1e-4), gi.ray_offset_max_voxels * gi.voxel_diagonal_m);
        vec3 o = origin + d * along;
        vec3 ray_o = ov + dir_to_voxel * (d * along);
        float ray_t = max(gi.radius_m - along, 0.0);
        VxHit h = voxel_first_hit(gi.dims, uint(gi.max_level), ray_o, dir_to_voxel * d, ray_t, gi.start_level, gi.max_iterations);
        vec3 l;
        if (h.hit) l = hit_radiance(h, o + d * h.t, d);
        else if (ENVIRONMENT != ENVIRONMENT_NONE) l = environment_after_miss(gi.dims, ray_o, dir_to_voxel * d, ray_t, h.ran_out, d);
        else continue;
        if (ggx) l *= w;
        else if (lobe) l *= cos_n;
        if (lobe) lobe_sum += l;
        else sum += l;
    }
    vec3 e = sum * (PI / float(max(diffuse_rays, 1u)));
    if (ggx) {
        // The indirect radiance (gi_composite's GGX_RADIANCE): (1 - m) b / pi E_weighted plus
        // the lobe's mean of L F G1.
        imageStore(irradiance, px, vec4(diffuse / PI * e + lobe_sum / float(max(lobe_rays, 1u)), 1.0));
    } else if (phong) {
        vec3 albedo = texelFetch(gb_albedo, px, 0).rgb;
        vec3 s = specular * ((ns.w + 2.0) / (ns.w + 1.0)) * lobe_sum / float(max(lobe_rays, 1u));
        imageStore(irradiance, px, vec4(albedo / PI * e + s, 1.0));
    } else {
        imageStore(irradiance, px, vec4(e, 1.0));
    }
}

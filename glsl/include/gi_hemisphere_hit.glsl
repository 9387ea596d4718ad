// The hemisphere method's radiance at a ray's hit (Thiedemann 2010, §6.3.3, §6.4.1), shared
// by its pass (gi_hemisphere_body.glsl) and the transparent layers' variants of oit_gather
// (oit_gather_hemisphere*.frag), so both read the same light: from the reflective light maps
// (default), plus the emission volume (EMISSION_FROM_VOLUME), or from the direct-radiance
// volume (RADIANCE_FROM_VOLUME). The includer declares `frame`, the `gi` block, the samplers
// and buffers the variant reads by these names (rlm_radiance, rlm_position, rlm_normal,
// materials, pbr; emission_volume, normal_volume; radiance_volume, material_volume,
// albedo_volume), the constants HAS_PHONG, HAS_GGX (and HAS_EMISSION with
// RADIANCE_FROM_VOLUME) and ENVIRONMENT, and includes voxel_traverse.glsl, shadow.glsl,
// brdf.glsl, material_lobe.glsl and environment.glsl first. hemisphere_ray (at the end) traces
// one of the method's rays and reads what it brings back.
#ifndef GI_HEMISPHERE_HIT_GLSL
#define GI_HEMISPHERE_HIT_GLSL
#include "paraboloid.glsl"
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

// What one of the method's rays brings back (Thiedemann 2010 §6.4.1): from `origin` (the
// point moved off its surface along the normal, §5.3.1; `ov` the same point in voxel space)
// along unit d, cos_n = d . n > 0, moved on along the ray by k2 h / cos_n, clamped (§5.3.1),
// so grazing rays leave their surface's own voxels too. Its first hit within gi.radius_m
// gives hit_radiance; a ray that leaves the voxel grid within that length the environment's
// radiance (ENVIRONMENT, environment.glsl: the sky's light, with voxel visibility). False
// where it brings nothing (a miss inside the grid, or no environment).
bool hemisphere_ray(vec3 origin, vec3 ov, vec3 d, float cos_n, out vec3 l) {
    mat3 dir_to_voxel = mat3(gi.world_to_voxel);
    float along = min(gi.ray_offset_voxels * gi.voxel_diagonal_m / max(cos_n, 1e-4), gi.ray_offset_max_voxels * gi.voxel_diagonal_m);
    vec3 o = origin + d * along;
    vec3 ray_o = ov + dir_to_voxel * (d * along);
    float ray_t = max(gi.radius_m - along, 0.0);
    VxHit h = voxel_first_hit(gi.dims, uint(gi.max_level), ray_o, dir_to_voxel * d, ray_t, gi.start_level, gi.max_iterations);
    l = vec3(0.0);
    if (h.hit) l = hit_radiance(h, o + d * h.t, d);
    else if (ENVIRONMENT != ENVIRONMENT_NONE) l = environment_after_miss(gi.dims, ray_o, dir_to_voxel * d, ray_t, h.ran_out, d);
    else return false;
    return true;
}

// The method's rays from a surface point p (unit normal n, the side lit; wo toward the camera;
// `rot` the pattern's Cranley-Patterson rotation) and what they bring back: `gi.rays` rays on
// Hammersley points, a Lambert receiver's all cosine-distributed, a Phong or GGX receiver's
// half on its specular lobe (a GGX metal, whose diffuse part is black, all of them; Thiedemann
// 2010 §5.7 for Phong). GGX rays are material_lobe.glsl's sample_lobe (visible normals
// weighted F(wo.h) G1(wi), or cosine samples weighted (1 - F_d(n.wi)) (1 - F_d(n.wo))), Phong
// lobe rays phong_direction's around the mirror direction (weighted by cos). Returns the sums
// of the diffuse rays' and the lobe rays' radiance and their counts: E = pi/N_d sum.
void hemisphere_gather(vec3 p, vec3 n, vec3 wo, vec2 rot, bool phong, float shininess, bool ggx,
                       Lobe receiver, out vec3 sum, out vec3 lobe_sum, out uint diffuse_rays,
                       out uint lobe_rays) {
    vec3 mirror = reflect(-wo, n);
    // Self-intersection offset along the normal (Thiedemann 2010 §5.3.1).
    vec3 origin = p + n * (gi.normal_offset_voxels * gi.voxel_diagonal_m);
    vec3 ov = (gi.world_to_voxel * vec4(origin, 1.0)).xyz;
    uint rays = max(gi.rays, 1u);
    lobe_rays = phong ? rays / 2u : 0u;
    if (ggx) lobe_rays = lobe_specular_probability(receiver) == 1.0 ? rays : rays / 2u;
    diffuse_rays = rays - lobe_rays;
    sum = vec3(0.0);
    lobe_sum = vec3(0.0);
    for (uint i = 0u; i < rays; ++i) {
        bool lobe = i >= diffuse_rays;
        uint j = lobe ? i - diffuse_rays : i;
        uint count = lobe ? lobe_rays : diffuse_rays;
        vec2 u = fract(vec2((float(j) + 0.5) / float(count), radical_inverse(j)) + rot);
        vec3 w = vec3(1.0);
        vec3 d = ggx ? sample_lobe(receiver, n, wo, lobe, u, w)
                     : (lobe ? phong_direction(mirror, shininess, u) : cosine_direction(n, u));
        float cos_n = dot(d, n);
        if (cos_n <= 0.0) continue;  // a lobe sample below the surface contributes nothing
        vec3 l;
        if (!hemisphere_ray(origin, ov, d, cos_n, l)) continue;
        if (ggx) l *= w;
        else if (lobe) l *= cos_n;
        if (lobe) lobe_sum += l;
        else sum += l;
    }
}

// A glossy receiver's indirect radiance from hemisphere_gather's sums and E: GGX (1 - m) b / pi
// E (E with the diffuse weights) plus the lobe's mean of L F G1 (gi_composite's
// GGX_RADIANCE); Phong rho_d / pi E plus rho_s (n + 2) / (n + 1) times the lobe's mean of L cos.
vec3 hemisphere_glossy_radiance(bool ggx, vec3 diffuse, vec3 specular, float shininess, vec3 e,
                                vec3 lobe_sum, uint lobe_rays) {
    if (ggx) return diffuse / PI * e + lobe_sum / float(max(lobe_rays, 1u));
    vec3 s = specular * ((shininess + 2.0) / (shininess + 1.0)) * lobe_sum / float(max(lobe_rays, 1u));
    return diffuse / PI * e + s;
}
#endif

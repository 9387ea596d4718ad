#version 450
// First-bounce VPL generation (Thiedemann 2010, §7.2): each invocation takes one point of the
// 2D Halton sequence (bases 2, 3) for one light and one interleaving set, turns it into a
// direction of the light's emission domain and reads the surface the light sees that way from
// the light's reflective map (the spot's view, or the cube face). A point light's directions
// are uniform on its sphere (Omega = 4 pi), each of solid angle Omega / K. A spot's are either
// uniform on its cone (SPOT_DISK off: Omega = 2 pi (1 - cos alpha), Omega / K each) or, as the
// thesis does, uniform in the disk the cone cuts from the spot's image plane (SPOT_DISK on,
// solid angle per sample in `disk_direction`). A directional light's point is a position on
// its orthographic map, each of equal area A / K.
//
// Photometry (§7.2): the light's flux into a sample's solid angle w is I * w, the VPL reflects
// Phi_VPL = rho * I * w. The map stores L = rho / pi * I f cos / d^2 (f Mitsuba's spot
// falloff, 1 for points), so rho * I f = L pi d^2 / cos: reading it from the map includes
// textures and the falloff. Directional: Phi_VPL = rho E_perp A / K = L pi A / (K cos).
// Glossy senders (vpl.glsl): the same read gives the diffuse part's Phi_VPL (a GGX texel
// stores (1 - m) b / pi (1 - F_d(n.wi)) E, light_map.frag, so Phi_VPL = (1 - m) b (1 - F_d) I f w),
// and the VPL also keeps the incident flux Phi_in = I f w (directional: E_perp A / K), the
// direction to the light and the lobe, so that the gather evaluates f(wi, wo) Phi_in cos
// toward each receiver.
//
// Samples that hit nothing stay in the set, flagged invalid with zero flux. NORMALIZE_VALID
// off (the default): their flux leaves the scene, so K (all samples of the domain) normalizes
// and the estimator is unbiased. On (the issue's and the thesis's "renormalize by the number
// of valid VPLs"): the light's whole flux is shared by the V valid samples of the set, each
// flux multiplied by K / V; exact when nothing misses (V = K), brighter where light leaves
// the scene. Counting V costs each invocation K map reads (`valid_count`).
#define GI_OWN_PUSH
#define VPL_GENERATE_PUSH
#include "frame.glsl"
#include "gi_common.glsl"
#include "vpl.glsl"

layout(local_size_x = 64) in;
layout(constant_id = 0) const bool NORMALIZE_VALID = false;
layout(constant_id = 1) const bool SPOT_DISK = false;
// The scene has GGX materials: their texels' senders get the GGX lobe.
layout(constant_id = 3) const bool HAS_GGX = false;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2DArray rlm_radiance;
layout(set = 0, binding = 2) uniform sampler2DArray rlm_position;
layout(set = 0, binding = 3) uniform sampler2DArray rlm_normal;
layout(set = 0, binding = 4, std430) writeonly buffer Vpls { GpuVpl vpls[]; };
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 5, std430) readonly buffer Materials { GpuMaterial materials[]; };
// GGX parameters per material (gbuffer.frag's table; read only when HAS_GGX).
struct GpuMaterialPbr { vec4 ggx; vec4 emission; uvec4 maps; };
layout(set = 0, binding = 6, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };

#include "shadow.glsl"
#include "paraboloid.glsl"

GpuVpl invalid_vpl() {
    return GpuVpl(vec4(0.0), vec4(0.0, 0.0, 1.0, 0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
}

// Texel of the light map that shows world point `p` in view `v`; false if outside.
bool map_texel(uint v, vec3 p, ivec2 size, out ivec2 q) {
    vec4 c = frame.shadow_views[v].view_proj * vec4(p, 1.0);
    q = ivec2(0);
    if (c.w <= 0.0) return false;
    // Paraboloid hemispheres (paraboloid.glsl): the direction's stereographic image.
    if (frame.shadow_views[v].params.y > 1.5 && c.z < 0.0) return false;
    vec2 ndc = frame.shadow_views[v].params.y > 1.5 ? paraboloid_uv(c.xyz) : c.xy / c.w;
    if (any(greaterThan(abs(ndc), vec2(1.0)))) return false;
    q = clamp(ivec2(floor((ndc * 0.5 + 0.5) * vec2(size))), ivec2(0), size - 1);
    return true;
}

// A spot's direction for Halton point u, uniform in the disk that the cone of half-angle
// alpha (cos alpha = cos_max) cuts from the image plane at focal distance f = 1 (Thiedemann
// 2010, §7.2): radius R = tan alpha, r = R sqrt(u.x), azimuth 2 pi u.y, so each sample stands
// for the area dA = pi R^2 / K. The solid angle a plane-area element covers is
// dw = cos(theta) dA / d^2 with d = f / cos(theta) its distance from the apex, so
// dw = cos^3(theta) dA / f^2, and Monte Carlo over the disk gives
// integral g dw = E[g cos^3 theta] pi R^2: the sample's weight is pi R^2 cos^3(theta) / K
// (their expected sum, integral over the disk of cos^3 dA = 2 pi (1 - cos alpha), is the
// cone's solid angle, so both spot samplings estimate the same flux).
vec3 disk_direction(vec3 axis, float cos_max, vec2 u, uint k, out float weight) {
    float tan2 = (1.0 - cos_max * cos_max) / (cos_max * cos_max);
    float r2 = tan2 * u.x;  // r^2 with r = tan(alpha) sqrt(u.x)
    float cos_t = inversesqrt(1.0 + r2);
    weight = PI * tan2 * cos_t * cos_t * cos_t / float(k);
    return around_axis(axis, cos_t, u.y);
}

// Halton point j of `l` as a texel q of map view v; weight: its solid angle (sr) or map area
// (m^2). False where the direction is outside every map (the sample hits nothing).
bool sample_texel(GpuLight l, uint j, ivec2 size, out uint v, out ivec2 q, out float weight) {
    vec2 u = vec2(halton(j, 2u), halton(j, 3u));
    uint k = max(pc.counts.z, 1u);
    if (l.info.x == LIGHT_DIRECTIONAL) {
        v = l.info.y;
        q = clamp(ivec2(floor(u * vec2(size))), ivec2(0), size - 1);
        // The map's side: meters per shadow texel times the shadow resolution.
        float side_m = frame.shadow_views[v].params.x * float(pc.trace.w);
        weight = side_m * side_m / float(k);
        return true;
    }
    bool spot = l.info.x == LIGHT_SPOT;
    float cos_max = spot ? l.spot.x : -1.0;
    vec3 axis = spot ? l.direction.xyz : vec3(0.0, 0.0, 1.0);
    vec3 d;
    if (spot && SPOT_DISK) {
        d = disk_direction(axis, cos_max, u, k, weight);
    } else {
        d = around_axis(axis, 1.0 - u.x * (1.0 - cos_max), u.y);
        weight = 2.0 * PI * (1.0 - cos_max) / float(k);
    }
    vec3 target = l.position.xyz + d;
    v = shadow_view_index(l, target);
    return map_texel(v, target, size, q);
}

// Whether Halton point j of `l` finds a surface in the light's map.
bool sample_valid(GpuLight l, uint j, ivec2 size) {
    uint v;
    ivec2 q;
    float weight;
    if (!sample_texel(l, j, size, v, q, weight)) return false;
    return texelFetch(rlm_position, ivec3(q, int(v)), 0).w != 0.0;
}

// V: the valid samples among the K of set `set_` this frame (halton_point).
uint valid_count(GpuLight l, uint set_, ivec2 size) {
    uint k = max(pc.counts.z, 1u);
    uint valid = 0u;
    for (uint kk = 0u; kk < k; kk++) {
        if (sample_valid(l, halton_point(set_, kk), size)) valid++;
    }
    return valid;
}

// The `light`-th of the frame's lights that have a reflective map: area-light samples
// (LIGHT_ELEMENT) have none and are skipped (their VPLs come from gi_vpl_emit.comp, which
// writes the emitter slot after this pass). False past the last.
bool map_light(uint light, out GpuLight l) {
    uint seen = 0u;
    for (uint i = 0u; i < frame.counts.x; ++i) {
        l = frame.lights[i];
        // Area lights (elements, and PCSS's whole spheres: spot.w > 0) are gi_vpl_emit's.
        if (l.info.x == LIGHT_ELEMENT || (l.info.x == LIGHT_POINT && l.spot.w > 0.0)) continue;
        if (seen == light) return true;
        seen++;
    }
    return false;
}

GpuVpl first_bounce(uint light, uint set_, uint j) {
    GpuLight l;
    if (!map_light(light, l) || l.info.z == 0u) return invalid_vpl();
    ivec2 size = textureSize(rlm_radiance, 0).xy;
    uint v;
    ivec2 q;
    float weight;  // the sample's solid angle (sr) or map area (m^2)
    if (!sample_texel(l, j, size, v, q, weight)) return invalid_vpl();
    vec4 pos = texelFetch(rlm_position, ivec3(q, int(v)), 0);
    if (pos.w == 0.0) return invalid_vpl();  // the light sees nothing there
    if (NORMALIZE_VALID) {
        // This sample is valid, so V >= 1.
        weight *= float(max(pc.counts.z, 1u)) / float(max(valid_count(l, set_, size), 1u));
    }
    vec3 n = normalize(texelFetch(rlm_normal, ivec3(q, int(v)), 0).xyz);
    vec3 radiance = texelFetch(rlm_radiance, ivec3(q, int(v)), 0).rgb;
    vec3 flux;
    vec3 incident;  // Phi_in: the light's flux into the sample's solid angle (or area)
    vec3 wl;        // unit direction to the light
    if (l.info.x == LIGHT_DIRECTIONAL) {
        wl = -l.direction.xyz;
        float cos_l = dot(n, wl);
        flux = cos_l > 1e-6 ? radiance * (PI * weight / cos_l) : vec3(0.0);
        incident = cos_l > 1e-6 ? l.intensity.rgb * weight : vec3(0.0);  // E_perp A / K
    } else {
        vec3 to_light = l.position.xyz - pos.xyz;
        float d2 = dot(to_light, to_light);
        wl = to_light * inversesqrt(max(d2, 1e-30));
        float cos_l = dot(n, wl);
        flux = cos_l > 1e-6 ? radiance * (PI * d2 * weight / cos_l) : vec3(0.0);
        float falloff = light_falloff(l, dot(-wl, l.direction.xyz));
        incident = cos_l > 1e-6 ? l.intensity.rgb * (falloff * weight) : vec3(0.0);
    }
    // Glossy senders (§7.3): the map holds only the diffuse part, Phi_VPL above. The VPL keeps
    // the lobe (vpl.glsl): the direction to the light wi, the incident flux Phi_in and the
    // material; a Phong sender's rho_s and exponent, a GGX sender's F0 = mix(0.04, b, m) and
    // roughness (kept at r >= 0.01, where D stays finite; b the material's base color, which
    // its albedo holds).
    uint material = max(uint(pos.w + 0.5), 1u) - 1u;
    GpuMaterial m = materials[material];
    if (HAS_GGX && pbr[material].ggx.z != 0.0) {
        vec4 ggx = pbr[material].ggx;
        vec3 f0 = mix(vec3(0.04), m.albedo.rgb, ggx.y);
        return GpuVpl(vec4(pos.xyz, 1.0), vec4(n, 0.0), vec4(flux, 0.0), vec4(wl, max(ggx.x, 0.01)),
                      vec4(f0, VPL_LOBE_GGX), vec4(incident, 0.0));
    }
    if (m.specular.a > 0.0 && any(greaterThan(m.specular.rgb, vec3(0.0)))) {
        return GpuVpl(vec4(pos.xyz, 1.0), vec4(n, 0.0), vec4(flux, 0.0), vec4(wl, m.specular.a),
                      vec4(m.specular.rgb, VPL_LOBE_PHONG), vec4(incident, 0.0));
    }
    return GpuVpl(vec4(pos.xyz, 1.0), vec4(n, 0.0), vec4(flux, 0.0), vec4(0.0), vec4(0.0), vec4(0.0));
}

void main() {
    uint lights = pc.counts.y;
    uint k = pc.counts.z;
    uint total = pc.counts.x * lights * k;
    uint i = gl_GlobalInvocationID.x;
    if (i >= total) return;
    uint set_ = i / (lights * k);
    uint light = (i / k) % lights;
    uint kk = i % k;
    // Each set takes its own K consecutive Halton points (halton_point): without temporal
    // accumulation the sets together are the first sets * K points, each set a stratified
    // subset.
    uint j = halton_point(set_, kk);
    vpls[vpl_index(set_, 0u, light, kk)] = first_bounce(light, set_, j);
}

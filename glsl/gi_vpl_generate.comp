#version 450
// First-bounce VPL generation (Thiedemann 2010, §7.2): each invocation takes one point of the
// 2D Halton sequence (bases 2, 3) for one light and one interleaving set, turns it into a
// direction of the light's emission domain — uniform on the spot's cone (solid angle
// Omega = 2 pi (1 - cos alpha)) or on the point light's sphere (Omega = 4 pi), both of equal
// solid angle per sample — and reads the surface the light sees that way from the light's
// reflective map (the spot's view, or the cube face). A directional light's point is a position
// on its orthographic map, each of equal area A / K.
//
// Photometry (§7.2): the light's flux into a sample's solid angle Omega / K is I * Omega / K,
// the VPL reflects Phi_VPL = rho * I * Omega / K. The map stores L = rho / pi * I f cos / d^2
// (f Mitsuba's spot falloff, 1 for points), so rho * I f = L pi d^2 / cos: reading it from the
// map includes textures and the falloff. Directional: Phi_VPL = rho E_perp A / K = L pi A / (K cos).
// Samples that hit nothing stay in the set, flagged invalid with zero flux: their flux leaves
// the scene, so K (all samples of the domain) normalizes, never the valid count alone.
#define GI_OWN_PUSH
#define VPL_GENERATE_PUSH
#include "frame.glsl"
#include "gi_common.glsl"
#include "vpl.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2DArray rlm_radiance;
layout(set = 0, binding = 2) uniform sampler2DArray rlm_position;
layout(set = 0, binding = 3) uniform sampler2DArray rlm_normal;
layout(set = 0, binding = 4, std430) writeonly buffer Vpls { GpuVpl vpls[]; };
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 5, std430) readonly buffer Materials { GpuMaterial materials[]; };

#include "shadow.glsl"

GpuVpl invalid_vpl() {
    return GpuVpl(vec4(0.0), vec4(0.0, 0.0, 1.0, 0.0), vec4(0.0), vec4(0.0), vec4(0.0));
}

// Texel of the light map that shows world point `p` in view `v`; false if outside.
bool map_texel(uint v, vec3 p, ivec2 size, out ivec2 q) {
    vec4 c = frame.shadow_views[v].view_proj * vec4(p, 1.0);
    q = ivec2(0);
    if (c.w <= 0.0) return false;
    vec2 ndc = c.xy / c.w;
    if (any(greaterThan(abs(ndc), vec2(1.0)))) return false;
    q = clamp(ivec2(floor((ndc * 0.5 + 0.5) * vec2(size))), ivec2(0), size - 1);
    return true;
}

GpuVpl first_bounce(uint light, uint j) {
    GpuLight l = frame.lights[light];
    if (light >= frame.counts.x || l.info.z == 0u) return invalid_vpl();
    vec2 u = vec2(halton(j, 2u), halton(j, 3u));
    ivec2 size = textureSize(rlm_radiance, 0).xy;
    uint k = max(pc.counts.z, 1u);
    uint v;
    ivec2 q;
    float weight;  // Omega / K (sr) or A / K (m^2)
    if (l.info.x == LIGHT_DIRECTIONAL) {
        v = l.info.y;
        q = clamp(ivec2(floor(u * vec2(size))), ivec2(0), size - 1);
        // The map's side: meters per shadow texel times the shadow resolution.
        float side_m = frame.shadow_views[v].params.x * float(pc.trace.w);
        weight = side_m * side_m / float(k);
    } else {
        bool spot = l.info.x == LIGHT_SPOT;
        float cos_max = spot ? l.spot.x : -1.0;
        vec3 axis = spot ? l.direction.xyz : vec3(0.0, 0.0, 1.0);
        vec3 d = around_axis(axis, 1.0 - u.x * (1.0 - cos_max), u.y);
        vec3 target = l.position.xyz + d;
        v = shadow_view_index(l, target);
        if (!map_texel(v, target, size, q)) return invalid_vpl();
        weight = 2.0 * PI * (1.0 - cos_max) / float(k);
    }
    vec4 pos = texelFetch(rlm_position, ivec3(q, int(v)), 0);
    if (pos.w == 0.0) return invalid_vpl();  // the light sees nothing there
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
    // Phong senders (§7.3): the glossy part leaves around the incident light's mirror
    // direction; the map holds only the diffuse part.
    GpuMaterial m = materials[max(uint(pos.w + 0.5), 1u) - 1u];
    bool glossy = m.specular.a > 0.0 && any(greaterThan(m.specular.rgb, vec3(0.0)));
    vec4 lobe = glossy ? vec4(reflect(-wl, n), m.specular.a) : vec4(0.0);
    vec4 specular = glossy ? vec4(m.specular.rgb * incident, 0.0) : vec4(0.0);
    return GpuVpl(vec4(pos.xyz, 1.0), vec4(n, 0.0), vec4(flux, 0.0), lobe, specular);
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
    // Each set takes its own K consecutive Halton points (index 0, the origin, is skipped):
    // the sets together are the first sets * K points, each set a stratified subset.
    uint j = set_ * k + kk + 1u;
    vpls[vpl_index(set_, 0u, light, kk)] = first_bounce(light, j);
}

// Shadow-map visibility with percentage-closer filtering (seeds/001, digest_001_004.md A.1-A.4).
// Depths are compared in meters along the view axis, with bias and normal offset measured in
// shadow-map texels, so the same settings work from millimeter to kilometer scenes.
// The including shader declares `frame` (a GpuFrame in a storage buffer) before including
// this file; it is read in place, never copied (it is several kilobytes).
#ifndef SHADOW_GLSL
#define SHADOW_GLSL
#include "frame.glsl"

// Linear distance along the view axis for a stored depth of a shadow view.
float shadow_linear_depth(GpuShadowView sv, float d) {
    float n = sv.params.z, f = sv.params.w;
    if (sv.params.y > 0.5) return n + d * (f - n);      // orthographic, paraboloid (radial)
    return n * f / (f - d * (f - n));                   // perspective, Vulkan [0, 1] depth
}

// Which shadow view of light `l` covers world point p (the cube face or paraboloid hemisphere
// for point lights).
uint shadow_view_index(GpuLight l, vec3 p) {
    uint first = l.info.y;
    if (l.info.z == 2u) {
        return dot(p - l.position.xyz, frame.shadow_views[first].axis.xyz) >= 0.0 ? first : first + 1u;
    }
    if (l.info.z < 6u) return first;
    vec3 d = p - l.position.xyz;
    vec3 a = abs(d);
    uint face;
    if (a.x >= a.y && a.x >= a.z) face = d.x > 0.0 ? 0u : 1u;
    else if (a.y >= a.z) face = d.y > 0.0 ? 2u : 3u;
    else face = d.z > 0.0 ? 4u : 5u;
    return first + face;
}

// Paraboloid hemispheres (shadow_depth.geom): uv = d.xy / (|d| + d.z) in the hemisphere frame
// (view_proj), depth = radial distance. The map is stereographic, hence conformal: a texel
// spans 2/res in uv, i.e. 2 (1 + z) / res radians at cos(angle to the axis) z, so at distance
// |d| one texel is params.x * |d| * (1 + z) meters (params.x = 2/res), between 1x at the rim
// and 2x at the axis of the cube map's 2/res per meter. Bias and normal offset use the same
// texel semantics as the other views. PCF taps past the rim (|uv| > 1) read the other
// hemisphere, whose frame shares x and y: there the same direction is at uv / |uv|^2.
float paraboloid_visibility(sampler2DArray maps, GpuShadowView sv, uint v, uint other, vec3 p,
                            vec3 n, float cos_theta) {
    vec3 d0 = (sv.view_proj * vec4(p, 1.0)).xyz;
    float dist0 = max(length(d0), 1e-30);
    float texel_m = sv.params.x * dist0 * (1.0 + max(d0.z, 0.0) / dist0);
    float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    vec3 po = p + n * (frame.shadow.z * texel_m * sin_theta);
    vec3 d = (sv.view_proj * vec4(po, 1.0)).xyz;
    float dist = length(d);
    if (dist >= sv.params.w) return 1.0;
    vec2 uv = d.xy / max(dist + d.z, 1e-30);
    ivec2 size = textureSize(maps, 0).xy;
    vec2 st = (uv * 0.5 + 0.5) * vec2(size);
    ivec2 center = ivec2(floor(st));
    float tan_theta = min(sin_theta / max(cos_theta, 1e-3), 10.0);
    float bias_m = texel_m * (frame.shadow.x + frame.shadow.y * tan_theta);
    int r = int(frame.shadow.w);
    float lit = 0.0, total = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            ivec2 q = center + ivec2(x, y);
            int layer = int(v);
            vec2 tuv = (vec2(q) + 0.5) / vec2(size) * 2.0 - 1.0;
            float t2 = dot(tuv, tuv);
            if (t2 > 1.0) {
                tuv /= t2;
                layer = int(other);
                q = clamp(ivec2(floor((tuv * 0.5 + 0.5) * vec2(size))), ivec2(0), size - 1);
            }
            total += 1.0;
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) { lit += 1.0; continue; }
            float stored = shadow_linear_depth(sv, texelFetch(maps, ivec3(q, layer), 0).r);
            lit += (dist - bias_m <= stored) ? 1.0 : 0.0;
        }
    }
    return lit / total;
}

// Fraction of the PCF footprint around p that the light reaches. n: unit surface normal,
// cos_theta: cosine between n and the direction to the light.
float shadow_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 n, float cos_theta) {
    if (l.info.z == 0u) return 1.0;
    uint v = shadow_view_index(l, p);
    GpuShadowView sv = frame.shadow_views[v];  // 96 bytes: one view, not the frame
    if (sv.params.y > 1.5) {
        // The light's two hemispheres are consecutive views.
        uint other = v == l.info.y ? v + 1u : l.info.y;
        return paraboloid_visibility(maps, sv, v, other, p, n, cos_theta);
    }
    // World size of one shadow texel at p.
    vec4 c0 = sv.view_proj * vec4(p, 1.0);
    float dist = sv.params.y > 0.5 ? 1.0 : max(c0.w, 1e-30);
    float texel_m = sv.params.x * dist;
    float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    vec3 po = p + n * (frame.shadow.z * texel_m * sin_theta);
    vec4 c = sv.view_proj * vec4(po, 1.0);
    if (c.w <= 0.0) return 1.0;
    vec3 ndc = c.xyz / c.w;
    if (ndc.z >= 1.0) return 1.0;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    ivec2 size = textureSize(maps, 0).xy;
    ivec2 center = ivec2(floor(uv * vec2(size)));
    float ref = shadow_linear_depth(sv, clamp(ndc.z, 0.0, 1.0));
    float tan_theta = min(sin_theta / max(cos_theta, 1e-3), 10.0);
    float bias_m = texel_m * (frame.shadow.x + frame.shadow.y * tan_theta);
    int r = int(frame.shadow.w);
    float lit = 0.0, total = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            ivec2 q = center + ivec2(x, y);
            total += 1.0;
            // Outside the map: not covered by this view, treated as lit (the spot cone or the
            // fitted directional frustum decides what is lit there).
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) { lit += 1.0; continue; }
            float stored = shadow_linear_depth(sv, texelFetch(maps, ivec3(q, int(v)), 0).r);
            lit += (ref - bias_m <= stored) ? 1.0 : 0.0;
        }
    }
    return lit / total;
}

#endif

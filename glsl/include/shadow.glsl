// Shadow-map visibility with percentage-closer filtering (Dachsbacher 2014, KIT lecture
// notes "Echtzeit-Schattenverfahren", part 3: shadow maps, PCF, bias, aliasing).
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
// for point lights; an area-light element's one hemisphere).
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

// Self-shadowing (shadow acne) and how the lookup avoids it.
//
// The map stores, per texel, the depth of the nearest surface at the texel's center. A PCF tap
// compares the receiver's depth with a texel center up to (r + 1/2) sqrt(2) texels from the
// receiver's own position in the map (floor of its texel coordinate plus the tap offset; r the
// kernel radius). If the receiver's own surface is stored there, it is a plane whose depth
// changes by tan(beta) per texel of lateral distance, beta being the angle between the
// surface normal and the axis along which depth is measured (the view axis for perspective
// and orthographic maps, the ray for the paraboloid's radial depth). The receiver then reads
// itself as an occluder unless the bias covers (r + 1/2) sqrt(2) tan(beta) texels, which has
// no bound as beta -> 90 degrees. That was the moire on the Cornell box's tall block, whose
// front face the spot light grazes at 87-89 degrees: a bias of 1 + min(tan, 10) texels and a
// normal offset of sin(theta) texels (worth tan(theta) texels of depth) covered
// 1 + 10 + tan texels, short of the 2.1 tan that the outer taps of the 3x3 kernel need from
// 84 degrees on; the dots are where the outer taps' texel centers fall behind the receiver
// (their grid beating against the pixel grid). It vanished with a 1x1 kernel, and the other
// suspects are far smaller: the D32 depth's precision (z^2 / near * 2^-24, under a third of a
// texel) and the G-buffer's reconstructed position (about 1e-5 m of 1e-3 m texels).
//
// Two remedies, each with a cost, are combined so that neither grows without bound. Let
// `reach` be the kernel's farthest texel center against the normal's lateral direction, times
// sin(beta) (texels; shadow_texel_and_reach). A point of the surface of constant depth
// through the lookup point, `reach` texels away, is then up to reach texels (in the normal's
// direction) behind the receiver's plane, which a tap sees as reach / cos(beta) texels of depth.
//  - A slope-scaled depth bias of reach / cos(beta) texels covers it, but at grazing angles a
//    large depth bias hides real occluders near the receiver (peter-panning), so it is capped
//    at `frame.shadow.y` texels.
//  - Moving the lookup point off the surface along its normal by k texels raises every point
//    of that constant-depth surface k texels above the plane (Holbert 2011, "normal offset
//    shadows"); its cost is that shadow edges move by up to k texels in the map.
// The bias takes what it can, the normal offset the rest: k = reach - bias cos(beta), which
// is 0 up to tan(beta) = cap / reach (about 63 degrees for a 3-texel cap and r = 1) and tends
// to reach (at most (r + 1/2) sqrt(2), 2.1 texels for r = 1) as beta -> 90 degrees. A planar
// receiver then never shadows itself at any angle. Moving along the normal lifts the point
// towards the light rather than sideways, so a contact shadow stays at its contact line. The
// constant bias (`frame.shadow.x` texels) and the depth format's rounding
// (shadow_depth_precision) come on top; `frame.shadow.z` adds a normal-offset margin.

// Depth error of a stored value at linear depth z, meters: 4 ulps of a D32 value near 1
// (2^-24 each), through d = f (z - n) / (z (f - n)) (perspective: dz/dd = z^2 (f - n) / (n f))
// or d = (z - n) / (f - n) (orthographic, paraboloid).
float shadow_depth_precision(GpuShadowView sv, float z) {
    float n = sv.params.z, f = sv.params.w;
    float dz_dd = sv.params.y > 0.5 ? f - n : z * z * (f - n) / max(n * f, 1e-30);
    return exp2(-22.0) * dz_dd;
}

// Normal offset and slope-scaled depth bias, both in texels, for a kernel `reach` texels
// against a normal at angle beta to the depth axis (see above).
vec2 shadow_offset_and_slope_bias(float reach, float sin_beta, float cos_beta) {
    float slope = min(reach / max(cos_beta, 1e-6), frame.shadow.y);
    float offset = max(reach - slope * cos_beta, 0.0) + frame.shadow.z * sin_beta;
    return vec2(offset, slope);
}

// Depth bias in meters: the constant and the slope part (texels), plus the depth format's
// rounding at depth z.
float shadow_depth_bias(GpuShadowView sv, float texel_m, float z, float slope_texels) {
    return texel_m * (frame.shadow.x + slope_texels) + shadow_depth_precision(sv, z);
}

// Paraboloid hemispheres (shadow_depth.geom): uv = d.xy / (|d| + d.z) in the hemisphere frame
// (view_proj), depth = radial distance. The map is stereographic, hence conformal: a texel
// spans 2/res in uv, i.e. 2 (1 + z) / res radians at cos(angle to the axis) z, so at distance
// |d| one texel is params.x * |d| * (1 + z) meters (params.x = 2/res), between 1x at the rim
// and 2x at the axis of the cube map's 2/res per meter. Depth is radial, so beta is the angle
// to the ray: sin(theta). PCF taps past the rim (|uv| > 1) read the other hemisphere, whose
// frame shares x and y: there the same direction is at uv / |uv|^2, rounded to that map's
// texel, which can add half a texel diagonal to the reach.
float paraboloid_texel_m(GpuShadowView sv, vec3 p) {
    vec3 d = (sv.view_proj * vec4(p, 1.0)).xyz;
    float dist = max(length(d), 1e-30);
    return sv.params.x * dist * (1.0 + max(d.z, 0.0) / dist);
}

float paraboloid_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 n, float cos_theta) {
    int r = int(frame.shadow.w);
    ivec2 size = textureSize(maps, 0).xy;
    float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    // The map's axes turn with the point, so the diagonal bound, plus the rim's rounding.
    float reach = (float(r) + 1.0) * sqrt(2.0) * sin_theta;
    vec2 os = shadow_offset_and_slope_bias(reach, sin_theta, cos_theta);
    // p's own hemisphere has the larger texel at p (1 + z with z >= 0 there), so it also
    // covers a moved point that crosses the rim.
    float texel_m = paraboloid_texel_m(frame.shadow_views[shadow_view_index(l, p)], p);
    vec3 po = p + n * (os.x * texel_m);
    // The hemisphere of the moved point, so that its own texel is inside its map.
    uint v = shadow_view_index(l, po);
    uint other = v == l.info.y ? v + 1u : l.info.y;
    GpuShadowView sv = frame.shadow_views[v];  // 96 bytes: one view, not the frame
    vec3 d = (sv.view_proj * vec4(po, 1.0)).xyz;
    float dist = length(d);
    if (dist >= sv.params.w) return 1.0;
    vec2 uv = d.xy / max(dist + d.z, 1e-30);
    vec2 st = (uv * 0.5 + 0.5) * vec2(size);
    ivec2 center = ivec2(floor(st));
    float bias_m = shadow_depth_bias(sv, texel_m, dist, os.y);
    float lit = 0.0, total = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            ivec2 q = center + ivec2(x, y);
            int layer = int(v);
            vec2 tuv = (vec2(q) + 0.5) / vec2(size) * 2.0 - 1.0;
            float t2 = dot(tuv, tuv);
            if (t2 > 1.0) {
                // An area-light element has one hemisphere and emits nothing behind it.
                if (l.info.z < 2u) { lit += 1.0; total += 1.0; continue; }
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

// World size of a texel of perspective or orthographic view sv at p, and for unit normal n
// the normal offset and slope bias in texels (see above). The map's x and y axes are the
// view's (rows 0 and 1 of view_proj, up to scale), so n's components a, b along them give
// sin(beta) = |(a, b)|, and the kernel's farthest texel center against the normal's lateral
// direction is (r + 1/2) (|a| + |b|) / |(a, b)| texels away (the sqrt(2) bound only on the
// diagonal): reach = (r + 1/2) (|a| + |b|).
vec3 shadow_texel_offset_slope(GpuShadowView sv, vec3 p, vec3 n, int r) {
    float z = sv.params.y > 0.5 ? 1.0 : max((sv.view_proj * vec4(p, 1.0)).w, 1e-30);
    mat4 m = sv.view_proj;
    float a = dot(n, normalize(vec3(m[0][0], m[1][0], m[2][0])));
    float b = dot(n, normalize(vec3(m[0][1], m[1][1], m[2][1])));
    float sin_beta = min(length(vec2(a, b)), 1.0);
    float cos_beta = sqrt(max(1.0 - sin_beta * sin_beta, 0.0));
    vec2 os = shadow_offset_and_slope_bias((float(r) + 0.5) * (abs(a) + abs(b)), sin_beta, cos_beta);
    return vec3(sv.params.x * z, os);
}

// Percentage-closer soft shadows (Fernando 2005; Oetke 2017 §4.3) of an area light drawn as
// one element at its centre (a rectangle) or as a point at its centre (a sphere, two
// hemispheres), with its size s = l.spot.w (m: the rectangle's √area, the sphere's
// diameter), in its paraboloid map.
//  1. Blocker search: 16 rotated Poisson taps over the region where blockers down to a fifth
//     of the receiver's distance can hide part of the light: a blocker at distance t from the
//     light, hiding the light's rim (s/2 off its centre) from p at distance z, lies
//     (s/2)(z/t - 1) from the ray light→p at the receiver's distance: 2 s for t = z/5.
//  2. Penumbra estimate from the mean blocker distance d_b, similar triangles:
//     w = s (z - d_b) / d_b at the receiver.
//  3. PCF with 16 rotated Poisson taps over a disk of radius w/2 at the receiver (32 taps
//     measured no better on area_light.toml: the residue is PCSS's bias, not its noise).
// Large kernels need receiver-plane depth: each tap compares the stored depth with the
// distance at which its texel's ray meets p's tangent plane, so a planar receiver never shadows
// itself at any kernel size; the constant bias and the format's rounding come on top.
const vec2 PCSS_POISSON[16] = vec2[](
    vec2(-0.9420, -0.3991), vec2(0.9456, -0.7689), vec2(-0.0942, -0.9294), vec2(0.3450, 0.2939),
    vec2(-0.9159, 0.4577), vec2(-0.8154, -0.8791), vec2(-0.3828, 0.2768), vec2(0.9748, 0.7565),
    vec2(0.4432, -0.9751), vec2(0.5374, -0.4737), vec2(-0.2650, -0.4189), vec2(0.7920, 0.1909),
    vec2(-0.2419, 0.9971), vec2(-0.8141, 0.9144), vec2(0.1998, 0.7864), vec2(0.1438, -0.1410));

// World direction of paraboloid-map coordinate uv of view sv (the stereographic map's inverse).
vec3 paraboloid_direction(GpuShadowView sv, vec2 uv) {
    float q = dot(uv, uv);
    return transpose(mat3(sv.view_proj)) * (vec3(2.0 * uv, 1.0 - q) / (1.0 + q));
}

// One tap at map coordinate uv: the stored distance and the distance of p's tangent plane
// (point p, normal n) along the tap texel's ray; x < 0 when the tap is off the map.
vec2 pcss_tap(sampler2DArray maps, GpuShadowView sv, uint layer, vec3 p, vec3 n, vec2 uv) {
    ivec2 size = textureSize(maps, 0).xy;
    ivec2 q = ivec2(floor((uv * 0.5 + 0.5) * vec2(size)));
    vec2 tuv = (vec2(q) + 0.5) / vec2(size) * 2.0 - 1.0;
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)) || dot(tuv, tuv) > 1.0) {
        return vec2(-1.0);
    }
    vec3 w = paraboloid_direction(sv, tuv);
    vec3 origin = transpose(mat3(sv.view_proj)) * -sv.view_proj[3].xyz;
    float wn = dot(w, n);
    float plane = wn < -1e-4 ? dot(p - origin, n) / wn : sv.params.w;
    float stored = shadow_linear_depth(sv, texelFetch(maps, ivec3(q, int(layer)), 0).r);
    return vec2(stored, plane);
}

float pcss_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 n) {
    // The element's one hemisphere, or the sphere's hemisphere that holds p.
    uint v = shadow_view_index(l, p);
    GpuShadowView sv = frame.shadow_views[v];
    vec3 d = (sv.view_proj * vec4(p, 1.0)).xyz;
    float z = length(d);
    if (z >= sv.params.w || z <= 0.0) return 1.0;
    vec2 uv = d.xy / max(z + d.z, 1e-30);
    float texel_m = paraboloid_texel_m(sv, p);
    // Meters at the receiver per unit of uv: a texel spans 2/res of uv.
    float m_per_uv = texel_m * float(textureSize(maps, 0).x) * 0.5;
    float s = l.spot.w;
    float bias_m = texel_m * frame.shadow.x + shadow_depth_precision(sv, z);
    // A rotation per receiver position (hashed), so the 16 taps' pattern does not band.
    float a = 6.2831853 * fract(sin(dot(p, vec3(12.9898, 78.233, 37.719))) * 43758.5453);
    mat2 rot = mat2(cos(a), sin(a), -sin(a), cos(a));
    float search_uv = 2.0 * s / m_per_uv;
    float blockers = 0.0, sum_m = 0.0;
    for (int i = 0; i < 16; ++i) {
        vec2 t = pcss_tap(maps, sv, v, p, n, uv + rot * PCSS_POISSON[i] * search_uv);
        if (t.x >= 0.0 && t.x < t.y - bias_m) {
            blockers += 1.0;
            sum_m += t.x;
        }
    }
    if (blockers == 0.0) return 1.0;
    float d_b = sum_m / blockers;
    float w_m = s * (z - d_b) / max(d_b, 1e-6);
    // At least the 3x3 PCF's footprint, so hard contact shadows stay antialiased.
    float radius_uv = max(0.5 * w_m / m_per_uv, 1.5 * 2.0 / float(textureSize(maps, 0).x));
    float lit = 0.0;
    for (int i = 0; i < 16; ++i) {
        vec2 t = pcss_tap(maps, sv, v, p, n, uv + rot * PCSS_POISSON[i] * radius_uv);
        lit += (t.x < 0.0 || t.x >= t.y - bias_m) ? 1.0 : 0.0;
    }
    return lit / 16.0;
}

// PCF over (2r+1)^2 texels of perspective or orthographic view v around the lookup point po
// (the receiver moved off its surface), with tos from shadow_texel_offset_slope.
float view_pcf_visibility(sampler2DArray maps, uint v, vec3 po, vec3 tos, int r) {
    GpuShadowView sv = frame.shadow_views[v];  // 96 bytes: one view, not the frame
    vec4 c = sv.view_proj * vec4(po, 1.0);
    if (c.w <= 0.0) return 1.0;
    vec3 ndc = c.xyz / c.w;
    if (ndc.z >= 1.0) return 1.0;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    ivec2 size = textureSize(maps, 0).xy;
    ivec2 center = ivec2(floor(uv * vec2(size)));
    // The view depth in meters straight from the clip coordinates (w for perspective), not
    // through the stored depth's nonlinear encoding, which would round it like a stored value.
    float ref = sv.params.y > 0.5 ? shadow_linear_depth(sv, clamp(ndc.z, 0.0, 1.0)) : c.w;
    float bias_m = shadow_depth_bias(sv, tos.x, ref, tos.z);
    // Taps past the edge of a perspective map (a spot's, or a cube face's, which its kernel
    // always fits) take the edge texel: the map holds the spot's whole cone, so only a kernel
    // or a lookup point's offsets at the cone's rim reach past it, and the edge texel holds the
    // occluder that shades them there. (Counting them as lit let a spot's light through the
    // leak benchmark's wall into the radiance volume's voxels at the rim.) Past an
    // orthographic map's edge lies what its fitted frustum leaves out, which is lit.
    bool clamp_to_edge = sv.params.y < 0.5;
    float lit = 0.0, total = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            ivec2 q = center + ivec2(x, y);
            total += 1.0;
            if (clamp_to_edge) q = clamp(q, ivec2(0), size - 1);
            else if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) { lit += 1.0; continue; }
            float stored = shadow_linear_depth(sv, texelFetch(maps, ivec3(q, int(v)), 0).r);
            lit += (ref - bias_m <= stored) ? 1.0 : 0.0;
        }
    }
    return lit / total;
}


// Fraction of the PCF footprint around p that the light reaches. n: unit surface normal,
// cos_theta: cosine between n and the direction to the light.
float shadow_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 n, float cos_theta) {
    if (l.info.z == 0u) return 1.0;
    if (frame.shadow_views[l.info.y].params.y > 1.5) {
        // PCSS: a rectangle drawn as one element, or a whole sphere (a point light of size
        // spot.w; regular point lights have 0 there).
        if ((l.info.x == LIGHT_ELEMENT || l.info.x == LIGHT_POINT) && l.spot.w > 0.0) {
            return pcss_visibility(maps, l, p, n);
        }
        return paraboloid_visibility(maps, l, p, n, cos_theta);
    }
    int r = int(frame.shadow.w);
    uint v = shadow_view_index(l, p);
    vec3 tos = shadow_texel_offset_slope(frame.shadow_views[v], p, n, r);
    float offset_m = tos.x * tos.y;
    // A cube face is wider than 90 degrees by r + 1 texels only, less than the offset can
    // move the point: the face is picked for the moved point (where its kernel fits), and
    // offset and bias are the larger of the two faces' when they differ.
    uint v2 = shadow_view_index(l, p + n * offset_m);
    if (v2 != v) {
        vec3 tos2 = shadow_texel_offset_slope(frame.shadow_views[v2], p, n, r);
        offset_m = max(offset_m, tos2.x * tos2.y);
        tos = max(tos, tos2);
        v = v2;
    }
    return view_pcf_visibility(maps, v, p + n * offset_m, tos, r);
}

// Cascaded shadow maps of a directional light (src/light/cascade.rs): GpuLight::info.w holds
// the first cascade view (low 16 bits) and the count (high 16 bits); each cascade view's
// axis.w is its far split in meters of camera view depth (the camera's clip w). The first
// cascade whose split lies beyond p's depth shades it; over the last CASCADE_BLEND of its
// depth range (from the previous split, or from 0) it fades into the next cascade, the last
// one into the light's whole-scene map, which also shades everything beyond the last split.
// Only the camera's direct light calls this; the GI passes keep shadow_visibility.
#define CASCADE_BLEND 0.1

float cascade_view_visibility(sampler2DArray maps, uint v, vec3 p, vec3 n) {
    int r = int(frame.shadow.w);
    vec3 tos = shadow_texel_offset_slope(frame.shadow_views[v], p, n, r);
    return view_pcf_visibility(maps, v, p + n * (tos.x * tos.y), tos, r);
}

// The view whose texels shade p for light l in the camera's direct light: its cascade (the
// one direct_shadow_visibility starts from) or the light's own view.
uint direct_shadow_view(GpuLight l, vec3 p) {
    uint count = l.info.w >> 16u;
    if (l.info.x == LIGHT_DIRECTIONAL && count > 0u) {
        uint first = l.info.w & 0xffffu;
        float depth = view_depth(frame.view_proj, frame.camera_position, frame.camera_forward, p);
        for (uint i = 0u; i < count; ++i) {
            if (depth <= frame.shadow_views[first + i].axis.w) return first + i;
        }
    }
    return shadow_view_index(l, p);
}

float direct_shadow_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 n, float cos_theta) {
    uint count = l.info.w >> 16u;
    if (l.info.x != LIGHT_DIRECTIONAL || count == 0u) return shadow_visibility(maps, l, p, n, cos_theta);
    uint first = l.info.w & 0xffffu;
    float depth = view_depth(frame.view_proj, frame.camera_position, frame.camera_forward, p);
    float prev = 0.0;
    for (uint i = 0u; i < count; ++i) {
        float split = frame.shadow_views[first + i].axis.w;
        if (depth <= split) {
            float vis = cascade_view_visibility(maps, first + i, p, n);
            float t = (split - depth) / max(CASCADE_BLEND * (split - prev), 1e-30);
            if (t >= 1.0) return vis;
            float next = i + 1u < count ? cascade_view_visibility(maps, first + i + 1u, p, n)
                                        : shadow_visibility(maps, l, p, n, cos_theta);
            // Equal values stay exact (a lit pixel is 1 in both, not 1 - 1 ulp).
            return next == vis ? vis : mix(next, vis, t);
        }
        prev = split;
    }
    return shadow_visibility(maps, l, p, n, cos_theta);
}

#endif

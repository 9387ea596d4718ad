#version 450
// VPLs from emitters (Thiedemann 2010, §7.2, with emitting surfaces as the light): emissive
// triangles and area lights (rectangles, spheres) in one table, sampled by emitted power. Each
// invocation takes Halton point j of its set (as gi_vpl_generate.comp does) and
//  1. picks emitter e with probability p_e = w_e A_e / W (w_e the mean of its radiance's
//     channels, A_e its area, W = sum of w A; u.x through the table's CDF, then rescaled into
//     the emitter's interval as the point's first coordinate), a point y uniform on it (pdf
//     1 / A_e) and its normal n there;
//     With an emission map (HAS_MAPS: map_Ke, src/voxel/maps.rs) the radiance varies over the
//     triangle, L_e(y) = Ke m(y) with m the map's texel at y (level 0, bilinear), and w_e is
//     the mean of Ke times the map's mean (Material::voxel_emission). The selection keeps that
//     table, and the point carries its own radiance: with y uniform, the joint pdf of (e, y)
//     is p_e / A_e = w_e / W, so the estimate of the flux Phi = sum_e pi int_{A_e} L_e(y) dy
//     is pi L_e(y) W / w_e = (pi W Ke / w_e) m(y) (the table's `flux` holds pi W Ke / w_e),
//     and E[.] = sum_e int_{A_e} (w_e / W) pi L_e(y) W / w_e dy = Phi: unbiased for any
//     weights that are positive wherever L_e is (w_e = 0 only for a black map, whose L_e is 0).
//     A uniform y wastes the samples that land where the map is dark (a stripe lit on a
//     quarter of its panel gets a quarter of them, each 4x brighter), so y is resampled
//     (resampled importance sampling, Talbot et al. 2005): M = MAP_CANDIDATES candidate points
//     x_1..x_M, each uniform on the triangle (pdf 1 / A_e; one Halton point shifted by an R2
//     lattice, so they are correlated, which RIS allows), target p^(x) = mean of m(x)'s
//     channels, one picked with probability p^(x_c) / sum_i p^(x_i); that point carries
//     m(y) / p^(y) * (1/M) sum_i p^(x_i) in place of m(y). Unbiased: for the integral
//     I = int_{A_e} m dy / A_e, E[m(y)/p^(y) (1/M) sum_i p^(x_i)]
//     = E_x[sum_c p^(x_c) / sum_i p^(x_i) * m(x_c)/p^(x_c) * (1/M) sum_i p^(x_i)]
//     = (1/M) sum_c E[m(x_c)] = I, each x_c being uniform by itself, given that p^ > 0
//     wherever m > 0 (a texel is black only if all its channels are); all candidates black
//     give a black point, as a uniform y there would. With M = 1 it is the uniform y above;
//  2. writes a source VPL at y for emissive surfaces: a Lambert emitter of radiance L sends the
//     intensity L A cos theta = (pi L A) / pi cos theta, a VPL of flux pi L A. One sample
//     estimates the emitter's whole flux Phi = sum_e pi L_e A_e as pi L_e A_e / p_e =
//     pi W L_e / w_e (the table stores that, `flux`), and K samples per set share it: each
//     carries pi W L_e / (w_e K), so the set's sum is unbiased. Area lights' points write an
//     invalid source VPL: their direct light is deferred_direct's (sampled sub-lights);
//  3. traces one cosine-distributed ray from y (pdf cos / pi: the direction a Lambert
//     emitter's flux leaves in) through the voxels, and at the first hit writes a VPL
//     reflecting Phi_s rho_hit (albedo and normal from the attribute volumes, as
//     gi_vpl_bounce.comp): the same estimator as a bounce from the source VPL. With Phong
//     or GGX materials (HAS_LOBES) a glossy hit keeps Phi_s as its incident flux and its
//     lobe (vpl.glsl's hit_vpl). A ray that leaves the grid carries its flux out of the scene
//     (an invalid VPL, no renormalization).
// The hit VPL is bounce 0 of the emitter slot (the last light of the row); gi_vpl_bounce.comp
// continues it like every other slot.
#define GI_OWN_PUSH
#define VPL_GENERATE_PUSH
#define VPL_HIT
#include "gi_common.glsl"
#include "brdf.glsl"
#include "material_lobe.glsl"
#include "vpl.glsl"

#define EMITTER_TRIANGLE 0.0   // origin, edges e1, e2: an emissive triangle (face normal e1 x e2)
#define EMITTER_RECTANGLE 1.0  // origin (a corner), edges e1, e2; normal e1 x e2
#define EMITTER_SPHERE 2.0     // origin the centre, e1.x the radius; normal outward

// Mirrors `GpuEmitter` in src/gi/gi_vpl_emit.rs.
struct GpuEmitter {
    vec4 origin;  // xyz (m); w the kind (EMITTER_*)
    vec4 edge1;   // xyz (m); the sphere's radius in x
    vec4 edge2;   // xyz (m)
    vec4 flux;    // rgb pi W L / w (W): one sample's flux times K (with a map L = Ke, times the
                  // map's texel at the point); w the CDF up to this emitter
    vec4 uv01;    // a triangle's texture coordinates at origin (xy), origin + edge1 (zw)
    vec4 uv2_map; // at origin + edge2 (xy); w the emission map (int bits, -1 none)
};

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform usampler2DArray voxels;
layout(set = 0, binding = 1, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 2) uniform sampler3D albedo_volume;
layout(set = 0, binding = 3) uniform sampler3D normal_volume;
layout(set = 0, binding = 4, std430) buffer Vpls { GpuVpl vpls[]; };
layout(set = 0, binding = 5, std430) readonly buffer Emitters { GpuEmitter emitters[]; };
// The material volume (src/voxel/attributes.rs, `material_texel`); read only when HAS_LOBES.
layout(set = 0, binding = 6) uniform sampler3D material_volume;
layout(constant_id = 3) const bool HAS_LOBES = false;
// Some emissive triangle has an emission map (read per texel; bound to the table otherwise).
layout(constant_id = 4) const bool HAS_MAPS = false;
// Candidate points per emitter sample on a triangle with an emission map (step 1).
const uint MAP_CANDIDATES = 8u;
#define VOXEL_MAPS_TEXELS_BINDING 7
#define VOXEL_MAPS_TABLE_BINDING 8
#include "voxel_maps.glsl"

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

// The first emitter whose CDF reaches u (binary search); u_in: u rescaled to [0, 1) inside
// that emitter's interval.
uint pick_emitter(float u, out float u_in) {
    uint lo = 0u;
    uint hi = uint(emitters.length()) - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (emitters[mid].flux.w < u) lo = mid + 1u;
        else hi = mid;
    }
    float below = lo > 0u ? emitters[lo - 1u].flux.w : 0.0;
    float width = emitters[lo].flux.w - below;
    u_in = clamp((u - below) / max(width, 1e-30), 0.0, 0.99999994);
    return lo;
}

// A point uniform on emitter e for u in [0, 1)^2, the normal there and (triangles) the
// point's barycentric weights on (origin, origin + edge1, origin + edge2).
vec3 emitter_point(GpuEmitter e, vec2 u, out vec3 n, out vec3 bary) {
    bary = vec3(1.0, 0.0, 0.0);
    if (e.origin.w == EMITTER_SPHERE) {
        // Uniform on the sphere: z uniform in [-1, 1] (Archimedes), azimuth 2 pi u.y.
        float z = 1.0 - 2.0 * u.x;
        float r = sqrt(max(1.0 - z * z, 0.0));
        float phi = 2.0 * PI * u.y;
        n = vec3(r * cos(phi), r * sin(phi), z);
        return e.origin.xyz + n * e.edge1.x;
    }
    n = normalize(cross(e.edge1.xyz, e.edge2.xyz));
    // A triangle folds the parallelogram's far half back onto itself (uniform in area).
    if (e.origin.w == EMITTER_TRIANGLE && u.x + u.y > 1.0) u = 1.0 - u;
    bary = vec3(1.0 - u.x - u.y, u.x, u.y);
    return e.origin.xyz + e.edge1.xyz * u.x + e.edge2.xyz * u.y;
}

GpuVpl invalid_vpl(uint bounce) {
    return GpuVpl(vec4(0.0), vec4(0.0, 0.0, 1.0, 0.0), vec4(0.0, 0.0, 0.0, float(bounce)), vec4(0.0), vec4(0.0), vec4(0.0));
}

void main() {
    uint k = max(pc.counts.z, 1u);
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.counts.x * k) return;
    uint set_ = i / k;
    uint kk = i % k;
    uint slot = pc.counts.y - 1u;  // the emitter slot: the row's last light
    uint j = halton_point(set_, kk);
    float u_in;
    GpuEmitter e = emitters[pick_emitter(halton(j, 2u), u_in)];
    vec3 n, bary;
    vec2 u = vec2(u_in, halton(j, 3u));
    vec3 y = emitter_point(e, u, n, bary);
    vec3 flux = e.flux.rgb / float(k);
    int map = floatBitsToInt(e.uv2_map.w);
    if (HAS_MAPS && e.origin.w == EMITTER_TRIANGLE && map >= 0) {
        // The map's radiance at resampled candidates (step 1): level 0, the map itself (a lod
        // far below any texel); the R2 lattice's generator (1/g, 1/g^2), g^3 = g + 1.
        const vec2 r2 = vec2(0.75487766624669276, 0.56984029099805327);
        vec4 uv2 = vec4(e.uv2_map.xy, 0.0, 0.0);
        vec3 m[MAP_CANDIDATES];
        float w[MAP_CANDIDATES];
        float sum = 0.0;
        for (uint c = 0u; c < MAP_CANDIDATES; ++c) {
            vec3 nc, bc;
            emitter_point(e, fract(u + float(c) * r2), nc, bc);
            m[c] = sample_voxel_map(map, voxel_map_uv(e.uv01, uv2, bc), -64.0).rgb;
            w[c] = max((m[c].r + m[c].g + m[c].b) / 3.0, 0.0);
            sum += w[c];
        }
        // Base 19: 17 picks gi_vpl_bounce.comp's lobes.
        float pick = halton(j, 19u) * sum;
        uint chosen = 0u;
        float below = 0.0;
        for (uint c = 0u; c < MAP_CANDIDATES; ++c) {
            if (w[c] > 0.0 && pick >= below) chosen = c;
            below += w[c];
        }
        vec3 b_chosen;
        y = emitter_point(e, fract(u + float(chosen) * r2), n, b_chosen);
        flux *= sum > 0.0 ? m[chosen] * (sum / (float(MAP_CANDIDATES) * w[chosen])) : vec3(0.0);
    }
    if (SOURCE_VPLS > 0u) {
        bool surface = e.origin.w == EMITTER_TRIANGLE;
        vpls[source_vpl_index(set_, kk)] = surface ? GpuVpl(vec4(y, 1.0), vec4(n, 0.0), vec4(flux, 0.0), vec4(0.0), vec4(0.0), vec4(0.0)) : invalid_vpl(0u);
    }
    // Bases 11 and 13: gi_vpl_bounce.comp takes 5 and 7 for the next bounce from the hit, so
    // the two directions stay independent.
    vec3 d = cosine_direction(n, vec2(halton(j, 11u), halton(j, 13u)));
    // Self-intersection offset along the normal (§5.3.1): emissive surfaces are voxelized.
    vec3 o = y + n * (pc.params.x * pc.params.y);
    vec3 ov = (pc.world_to_voxel * vec4(o, 1.0)).xyz;
    VxHit h = voxel_first_hit(pc.dims.xyz, uint(pc.dims.w), ov, mat3(pc.world_to_voxel) * d, pc.params.z, pc.trace.x, pc.trace.y);
    uint dst = vpl_index(set_, 0u, slot, kk);
    if (!h.hit) {
        vpls[dst] = invalid_vpl(0u);
        return;
    }
    ivec3 v = ivec3(h.voxel);
    vec3 albedo = texelFetch(albedo_volume, v, 0).rgb;
    vec3 hn = texelFetch(normal_volume, v, 0).xyz;
    hn = dot(hn, hn) > 0.25 ? normalize(hn) : -d;
    if (dot(hn, d) > 0.0) hn = -hn;  // the side the ray arrives at
    Lobe hit = HAS_LOBES ? voxel_lobe(albedo, texelFetch(material_volume, v, 0)) : lambert_lobe(albedo);
    vpls[dst] = hit_vpl(o + d * h.t, hn, d, flux, hit, 0.0);
}

// Transparent layers into per-pixel linked lists (Yang et al. 2010, "Real-time concurrent
// linked list construction on the GPU"; Dachsbacher 2014, part 3, order-independent
// transparency): every fragment of a material with MTL d < 1 that lies in front of the opaque
// depth (tested, not written) is shaded with the deferred pass's direct light
// (direct_light.glsl) plus its emission, then appended to a node buffer through an atomic
// counter, its node pointing at the pixel's previous head (an r32ui image, ~0u = end). A
// fragment past the buffer's capacity is dropped; the counter still counts it, so the host
// reads how many were lost. oit_resolve.comp sorts and blends the lists.
// Shaded from the constant material values and the albedo map (no bump or PBR maps).
//
// Body of oit_gather.frag (direct light and emission), oit_gather_indirect.frag
// (VOXEL_INDIRECT: plus the voxel path tracer's indirect light, see voxel_irradiance) and
// oit_gather_hemisphere*.frag (HEMISPHERE_INDIRECT: plus the hemisphere method's one bounce,
// a glossy layer's lobe included, its rays cast and read by gi_hemisphere_hit.glsl: light maps, with EMISSION_FROM_VOLUME
// the emission volume too, or with RADIANCE_FROM_VOLUME the direct-radiance volume) and
// oit_gather_vpl.frag (VPL_INDIRECT: plus the frame's VPLs, gathered as gi_vpl_gather does).
layout(early_fragment_tests) in;  // a fragment behind the opaque depth appends nothing

layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 2) const bool HAS_TEXTURES = false;
// Some material has an alpha map (alpha_map.glsl): per-texel opacity (blend), or a cutout.
layout(constant_id = 3) const bool HAS_ALPHA_MAP = false;

struct GpuMaterial {
    vec4 albedo;    // rgb albedo, a opacity
    vec4 specular;  // rgb specular reflectance, a shininess
    uvec4 flags;    // x: an albedo texture replaces albedo (gbuffer.frag)
};
struct GpuMaterialPbr {
    vec4 ggx;       // x roughness, y metallic, z 1 for a GGX material
    vec4 emission;  // rgb W/(m^2 sr)
    uvec4 maps;     // 1 where the draw's map is used: x roughness, y metallic, z emission
};

#include "frame.glsl"
#include "brdf.glsl"
#include "alpha_map.glsl"
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#include "shadow.glsl"
#include "direct_light.glsl"
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// The draw's albedo texture (a 1x1 placeholder when the material has none).
layout(set = 0, binding = 2) uniform sampler2D albedo_texture;
layout(set = 0, binding = 3, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };
layout(set = 0, binding = 4) uniform sampler2DArray shadow_maps;
// Head of each pixel's list: the index of its nearest-appended node, ~0u for none.
layout(set = 0, binding = 5, r32ui) uniform coherent uimage2D heads;
// Node: x packHalf2x16(r, g), y packHalf2x16(b, alpha), z depth (float bits), w next.
layout(set = 0, binding = 6, std430) writeonly buffer Nodes { uvec4 nodes[]; };
// x: nodes requested this frame (may exceed y), y: capacity; z, w: oit_resolve's counts.
layout(set = 0, binding = 7, std430) coherent buffer Counters { uvec4 counters; };

#if defined(VOXEL_INDIRECT) || defined(HEMISPHERE_INDIRECT) || defined(VPL_INDIRECT)
#define LAYER_INDIRECT
#endif

#ifdef LAYER_INDIRECT
#define GI_OWN_PUSH
#ifndef VPL_INDIRECT
// The GI method's ray parameters (src/gi/gi_common.rs's GpuGiPush, the ray passes' push
// constants), in a buffer: this pass's push constants hold the draw's transform.
struct GpuGiPush {
    mat4 world_to_voxel;
    ivec3 dims;
    int max_level;
    float radius_m;
    float normal_offset_voxels;
    float hit_tolerance_voxels;
    float voxel_diagonal_m;
    uint rays;
    uint start_level;
    uint max_iterations;
    uint seed;
    float light_map_scale;
    uint bounces;
    float ray_offset_voxels;
    float ray_offset_max_voxels;
};
layout(set = 0, binding = 8, std430) readonly buffer GiParams { GpuGiPush gi; };
#endif
layout(set = 0, binding = 9) uniform usampler2DArray voxels;
layout(set = 0, binding = 10, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
#include "gi_common.glsl"

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
#include "material_lobe.glsl"
#endif

#if defined(VOXEL_INDIRECT) || defined(HEMISPHERE_INDIRECT)
// The environment (environment.glsl's kinds): the layers' rays that leave the voxel grid read
// it, as the opaque passes' rays do. The VPLs bring none (a VPL starts at a light).
layout(constant_id = 8) const uint ENVIRONMENT = 0u;
layout(set = 0, binding = 16) uniform sampler2D environment_map;  // a placeholder unless a map
#include "environment.glsl"
#endif

#ifdef VOXEL_INDIRECT
// The hit voxel's emission is added where a path arrives on an emitter's front side.
layout(constant_id = 4) const bool HAS_EMISSION = false;
layout(set = 0, binding = 11) uniform sampler3D albedo_volume;
layout(set = 0, binding = 12) uniform sampler3D normal_volume;
layout(set = 0, binding = 13) uniform sampler3D emission_volume;  // albedo when !HAS_EMISSION
#include "voxel_path.glsl"

// Irradiance at the fragment p (normal n, the side the camera sees) by gi_pathtrace.comp's
// paths: `gi.rays` cosine-distributed paths of `gi.bounces` bounces (0: Russian roulette
// after ROULETTE_AFTER), the same bounce samples, offsets and next-event estimation from the
// shadow maps at every hit, later bounces Lambert with the albedo volume's colour, an
// emitter's front side adding its emission, a path that leaves the grid the environment's
// radiance. E = pi/N sum L (cosine sampling). What the path tracer does besides is left out:
// no emitter or environment-map sampling (next-event estimation toward them), so an emitter's
// or the map's light arrives only where a path meets it, unbiased but noisier. One frame's
// estimate with a fixed
// per-pixel pattern (gi.seed): the layer is shaded anew every frame and has no history to
// accumulate into, so a still view keeps its noise rather than flickering.
vec3 voxel_irradiance(vec3 p, vec3 n, uvec2 px) {
    uint rays = max(gi.rays, 1u);
    bool roulette = gi.bounces == 0u;
    uint bounces = roulette ? MAX_PATH_BOUNCES : gi.bounces;
    float offset = gi.normal_offset_voxels * gi.voxel_diagonal_m;
    vec2 rot = pixel_rotation(px, gi.seed);
    vec3 sum = vec3(0.0);
    for (uint s = 0u; s < rays; ++s) {
        vec3 o = p + n * offset;
        vec3 nn = n;
        vec3 throughput = vec3(1.0);
        for (uint b = 0u; b < bounces; ++b) {
            vec3 d = cosine_direction(nn, bounce_sample(b, s, rays, gi.seed, rot));
            if (roulette && b >= ROULETTE_AFTER) {
                float q = min(max(throughput.r, max(throughput.g, throughput.b)), 0.95);
                if (roulette_sample(px, gi.seed * rays + s, b) >= q) break;
                throughput /= q;
            }
            vec3 start;
            VxHit h = trace_from(o, nn, d, start);
            if (!h.hit) {
                // A path that leaves the grid brings the environment's radiance, as the path
                // tracer's BSDF rays do (weight 1: the layer draws no map samples to share it).
                if (ENVIRONMENT != ENVIRONMENT_NONE) sum += throughput * escaped_radiance(o, start, d, h);
                break;
            }
            ivec3 v = ivec3(h.voxel);
            vec3 a = texelFetch(albedo_volume, v, 0).rgb;
            vec4 nd = texelFetch(normal_volume, v, 0);
            vec3 hn = dot(nd.xyz, nd.xyz) > 0.25 ? normalize(nd.xyz) : -d;
            bool back = dot(hn, d) > 0.0;
            if (back) hn = -hn;  // the side the ray arrives at
            if (HAS_EMISSION && !back) {
                // The half-float emission volume holds pre-exposed radiance (frame.glsl).
                sum += throughput * texelFetch(emission_volume, v, 0).rgb * frame.radiance_scale.y;
            }
            vec3 hs = voxel_surface_point(gi.world_to_voxel, v, nd, start, d, h.t);
            sum += throughput * direct_at(hs, hn, -d, lambert_lobe(a));
            // The next bounce is cosine-sampled from a Lambert surface: its weight is the
            // albedo. It starts back along the ray, as the path tracer's does.
            throughput *= a;
            o = start + d * h.t - d * min(offset, h.t);
            nn = hn;
        }
    }
    return sum * (PI / float(rays));
}
#endif

#ifdef VPL_INDIRECT
#include "vpl.glsl"
#include "vpl_gather.glsl"
// The VPL gather's parameters (src/gi/vpl.rs's GpuVplGatherPush, gi_vpl_gather's push
// constants) in a buffer, and the frame's VPLs, written by gi_vpl_generate, gi_vpl_emit and
// gi_vpl_bounce before the layers are drawn.
layout(set = 0, binding = 8, std430) readonly buffer VplParams { GpuVplGatherPush vg; };
layout(set = 0, binding = 11, std430) readonly buffer Vpls { GpuVpl vpls[]; };

// Irradiance at the fragment p (normal n, the side the camera sees) from the frame's VPLs, each
// by the opaque gather's term (vpl_arriving: E = I(w) cos theta_P / (d_min + d^2) with the
// method's visibility test). The opaque pixels gather one of the N x M interleaved sets each
// and the geometry-aware filter blends the sets across the pattern (Thiedemann 2010 §7.3.2);
// a layer has no filter, so it gathers every set and takes their mean: each row is a complete
// estimator of the indirect light, so the mean of the N M rows is the method's estimate with
// all of its VPLs, at one visibility ray per VPL. The VPLs are the frame's own (the same
// Halton points every frame without temporal accumulation), so a still view keeps its pattern.
vec3 voxel_irradiance(vec3 p, vec3 n, uvec2 px) {
    uint sets = max(vg.pattern.x, 1u) * max(vg.pattern.y, 1u);
    uint count = sets * vg.pattern.z;
    vec3 e = vec3(0.0);
    for (uint i = 0u; i < count; ++i) {
        vec3 dir, arriving;
        if (vpl_arriving(vg, vpls[i], p, n, dir, arriving)) e += arriving;
    }
    return e / float(sets);
}
#endif

#ifdef HEMISPHERE_INDIRECT
#ifdef RADIANCE_FROM_VOLUME
// A glossy hit's specular lobe reads the material, base colour and emission volumes (the
// albedo volume fills the material and emission bindings where the shader never reads them).
layout(constant_id = 4) const bool HAS_EMISSION = false;
layout(set = 0, binding = 11) uniform sampler3D radiance_volume;  // rgb radiance, a: lit side
layout(set = 0, binding = 12) uniform sampler3D normal_volume;
layout(set = 0, binding = 13) uniform sampler3D material_volume;
layout(set = 0, binding = 14) uniform sampler3D albedo_volume;
layout(set = 0, binding = 15) uniform sampler3D emission_volume;
#else
layout(set = 0, binding = 11) uniform sampler2DArray rlm_radiance;
layout(set = 0, binding = 12) uniform sampler2DArray rlm_position;
layout(set = 0, binding = 13) uniform sampler2DArray rlm_normal;
#ifdef EMISSION_FROM_VOLUME
layout(set = 0, binding = 14) uniform sampler3D emission_volume;
layout(set = 0, binding = 15) uniform sampler3D normal_volume;
#endif
#endif
#include "gi_hemisphere_hit.glsl"

// Indirect radiance toward wo of the fragment p (normal n, the side the camera sees; diffuse
// colour `albedo`, the lobe and its parameter as direct_radiance takes them) by the hemisphere
// method's rays, cast and read by the very function gi_hemisphere_body.glsl calls
// (hemisphere_gather: `gi.rays` rays on Hammersley points under the per-pixel rotation of
// gi.seed, a Phong or GGX layer's half on its specular lobe, each ray's radiance from
// hit_radiance at a hit and past the grid the environment's) and composed as a G-buffer pixel
// of that material is: albedo/pi E for Lambert, hemisphere_glossy_radiance for Phong and GGX.
// One bounce, as the method's. One frame's estimate with a fixed pattern, as the path tracer's
// variant above: the layer has no history.
vec3 hemisphere_layer_radiance(vec3 p, vec3 n, vec3 wo, uvec2 px, vec3 albedo, vec4 lobe,
                               float lobe_parameter) {
    bool ggx = HAS_GGX && lobe.w > 1.5;
    vec3 specular = ggx ? vec3(0.0) : lobe.rgb;
    bool phong = HAS_PHONG && !ggx && is_phong_pixel(specular);
    Lobe receiver = Lobe(LOBE_GGX, albedo, lobe.rgb, lobe_parameter);
    vec3 sum, lobe_sum;
    uint diffuse_rays, lobe_rays;
    hemisphere_gather(p, n, wo, pixel_rotation(px, gi.seed), phong, lobe_parameter, ggx,
                      receiver, sum, lobe_sum, diffuse_rays, lobe_rays);
    vec3 e = sum * (PI / float(max(diffuse_rays, 1u)));
    if (ggx || phong) {
        return hemisphere_glossy_radiance(ggx, albedo, specular, lobe_parameter, e, lobe_sum, lobe_rays);
    }
    return albedo / PI * e;
}
#endif

layout(push_constant) uniform Push {
    mat4 model;
    uint material;
    // Rows of prev_model · model⁻¹ (the draw's world motion since the previous frame; a
    // row vector times it gives the point's previous world position): gbuffer.frag's motion
    // vectors only.
    mat3x4 motion;
} pc;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec3 in_world;

void main() {
    GpuMaterial m = materials[pc.material];
    GpuMaterialPbr mp = pbr[pc.material];
    vec3 n = normalize(in_normal);
    // Two-sided, as in gbuffer.frag: shade the side the camera sees.
    bool front = dot(n, toward_camera(frame.camera_position, frame.camera_forward, in_world)) >= 0.0;
    if (!front) n = -n;
    vec3 albedo = m.albedo.rgb;
    vec4 texel = HAS_TEXTURES ? texture(albedo_texture, vec2(in_uv.x, 1.0 - in_uv.y)) : vec4(1.0);
    if (HAS_TEXTURES && m.flags.x != 0u) albedo = texel.rgb;
    float opacity = HAS_ALPHA_MAP ? alpha_map_opacity(m.flags.w, m.albedo.a, texel.a) : m.albedo.a;
    // Cut away (or fully clear): no layer.
    if (HAS_ALPHA_MAP && opacity <= 0.0) return;
    vec4 lobe = vec4(m.specular.rgb, 1.0);
    float lobe_parameter = m.specular.a;
    if (HAS_GGX && mp.ggx.z != 0.0) {
        lobe = vec4(mix(vec3(0.04), albedo, mp.ggx.y), 2.0);
        lobe_parameter = mp.ggx.x;
        albedo *= 1.0 - mp.ggx.y;
    }
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, in_world);
    vec3 lo = direct_radiance(shadow_maps, in_world, n, wo, albedo, lobe, lobe_parameter);
#ifdef HEMISPHERE_INDIRECT
    // The hemisphere method's indirect radiance, a glossy layer's lobe included, as
    // gi_composite adds it to a G-buffer pixel, on the side the camera sees.
    lo += hemisphere_layer_radiance(in_world, n, wo, uvec2(gl_FragCoord.xy), albedo, lobe, lobe_parameter);
#elif defined(LAYER_INDIRECT)
    // The diffuse part's indirect light, albedo/pi E, as gi_composite adds it to a Lambert
    // G-buffer pixel, on the side the camera sees (Mitsuba's mask around a diffuse BSDF
    // reflects from the side it is hit; what lies behind is the blend's).
    lo += albedo / PI * voxel_irradiance(in_world, n, uvec2(gl_FragCoord.xy));
#endif
    // Emission leaves the front side only, as Mitsuba's area emitter.
    if (front) lo += mp.emission.rgb;
    // The node holds half floats: pre-exposed radiance (frame.glsl; oit_resolve scales back).
    lo *= frame.radiance_scale.x;

    uint index = atomicAdd(counters.x, 1u);
    if (index >= counters.y) return;  // full: dropped, and counted by counters.x
    uint next = imageAtomicExchange(heads, ivec2(gl_FragCoord.xy), index);
    nodes[index] = uvec4(packHalf2x16(lo.rg), packHalf2x16(vec2(lo.b, opacity)),
                         floatBitsToUint(gl_FragCoord.z), next);
}

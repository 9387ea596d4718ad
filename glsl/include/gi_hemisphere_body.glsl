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

#include "gi_hemisphere_hit.glsl"

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
    // GGX receivers (HAS_GGX): F0 in the lobe target, the roughness in the normal's w, the
    // diffuse color (1 - m) b in the albedo (docs/ARCHITECTURE.md, "Materials").
    vec4 lobe_texel = HAS_GGX ? texelFetch(gb_specular, px, 0) : vec4(0.0);
    bool ggx = HAS_GGX && lobe_texel.a > 1.5;
    vec3 diffuse = ggx ? texelFetch(gb_albedo, px, 0).rgb : vec3(0.0);
    Lobe receiver = Lobe(LOBE_GGX, diffuse, lobe_texel.rgb, ns.w);
    vec2 rot = ADVANCE ? fract(pixel_rotation(uvec2(px), 0u) + r2(gi.seed))
                       : pixel_rotation(uvec2(px), gi.seed);
    // The rays (gi_hemisphere_hit.glsl, which transparent layers call too).
    vec3 sum, lobe_sum;
    uint diffuse_rays, lobe_rays;
    hemisphere_gather(p, n, wo, rot, phong, ns.w, ggx, receiver, sum, lobe_sum, diffuse_rays, lobe_rays);
    vec3 e = sum * (PI / float(max(diffuse_rays, 1u)));
    if (ggx) {
        imageStore(irradiance, px, vec4(hemisphere_glossy_radiance(true, diffuse, vec3(0.0), ns.w, e, lobe_sum, lobe_rays), 1.0));
    } else if (phong) {
        vec3 albedo = texelFetch(gb_albedo, px, 0).rgb;
        imageStore(irradiance, px, vec4(hemisphere_glossy_radiance(false, albedo, specular, ns.w, e, lobe_sum, lobe_rays), 1.0));
    } else {
        imageStore(irradiance, px, vec4(e, 1.0));
    }
}

// Body of gi_vpl_gather.comp (every VPL of the set in one loop) and gi_vpl_splat.comp
// (VPL_SPLAT: one pass per VPL index, each adding that VPL to the image, as the thesis's
// additive splatting; the first pass writes, the others read and add).
//
// VPL shading with interleaved sampling (Thiedemann 2010, §7.3, §7.3.2). The frame is split
// into N x M blocks, block (i, j) holding the pixels (x, y) with x mod N = i, y mod M = j, and
// each block is shaded with its own VPL set s = j N + i; the inverse split writes each result
// back to its pixel. Both splits are index maps of this dispatch — invocation (bx, by) of
// block (i, j) shades pixel (bx N + i, by M + j) — so no G-buffer copy is made, and a
// workgroup never straddles two blocks: all its invocations read the same VPL row. Blocks are
// ceil(W / N) x ceil(H / M); invocations past the frame's edge (sizes that are not a multiple
// of the pattern) do nothing. The geometry-aware filter then removes the pattern.
//
// Each valid VPL is a cosine emitter of I(w) = I_max cos theta_VPL, I_max = Phi_VPL / pi (glossy
// senders, Phong or GGX: I(w) = f(wi, w) Phi_in cos theta_VPL, vpl_intensity in vpl.glsl), and
// gives a receiver point E = I(w) cos theta_P / (d_min + d^2) (§7.3), times
// the visibility of the segment from the voxel ray test (offsets at both ends, §5.3.1), or 1
// without visibility (vpl_arriving in vpl_gather.glsl, which transparent layers call too).
// d_min (the thesis's clamp) bounds the 1/d^2 singularity of every VPL, glossy ones
// included: E <= I_max / d_min. A glossy VPL's intensity is bounded as well, by its lobe's
// peak (GGX: D <= 1 / (pi alpha^2) with alpha >= 1e-4; Phong: (n + 2) / (2 pi)), but not
// clamped further: a sharp lobe's VPL lights a small spot brightly, as the lobe does.
// Lambert pixels store E; Phong pixels their indirect radiance,
// rho / pi E plus the Phong lobe rho_s (n+2)/(2 pi) cos^n(alpha) times I cos theta_P / (d_min + d^2);
// GGX pixels their indirect radiance, the sum of f_r(wi, wo) I cos theta_P / (d_min + d^2) with
// brdf.glsl's whole brdf_ggx (wi toward the VPL, wo toward the camera).
//
// Glossy receivers: a receiver's lobe turns each VPL into a highlight as sharp as the lobe, which
// a finite VPL set cannot fill in (Thiedemann 2010 §7.3: "high exponents need very many VPLs";
// the receiver-side twin of the sender's blotches). The receiver's lobe is therefore widened to
// a roughness floor r >= MIN_ROUGHNESS (`--vpl-min-roughness`; Phong: n <= 2 / r^4 - 2, the
// exponent of the GGX width alpha = r^2, Walter et al. 2007), which bounds its peak (GGX:
// D <= 1 / (pi alpha^2)) and so every VPL's radiance to a glossy pixel, as d_min bounds 1/d^2.
// It biases only receivers smoother than the floor: a mirror-like receiver shows the VPL-lit
// scene blurred to the floor's lobe, not a sharp reflection (that is screen-space GI's SSR).
#define GI_OWN_PUSH
#include "frame.glsl"
#include "gi_common.glsl"
#include "brdf.glsl"
#include "vpl.glsl"
#include "gbuffer_lobe.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;
// Some material is GGX: GGX pixels are shaded with their whole BRDF.
layout(constant_id = 1) const bool HAS_GGX = false;
// The glossy receivers' roughness floor (above), perceptual roughness.
layout(constant_id = 2) const float MIN_ROUGHNESS = 0.0;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform usampler2DArray voxels;
layout(set = 0, binding = 4, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 5, std430) readonly buffer Vpls { GpuVpl vpls[]; };
#ifdef VPL_SPLAT
layout(set = 0, binding = 6, rgba32f) uniform image2D irradiance;
#else
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D irradiance;
#endif
layout(set = 0, binding = 7) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 8) uniform sampler2D gb_albedo;

// Mirrors `GpuVplGatherPush` in src/gi/vpl.rs (both shaders).
layout(push_constant) uniform VplGatherPush {
    mat4 world_to_voxel;
    ivec4 dims;          // voxels x, y, depth; w max hierarchy level
    uvec4 pattern;       // x N, y M, z VPLs per row, w visibility (1: voxel test, 0: none)
    uvec2 trace;         // x start level, y max iterations
    float d_min_m2;      // d_min of E = I cos cos / (d_min + d^2), m^2
    float voxel_diagonal_m;
    vec3 offsets;        // x normal offset, y ray offset k2, z its clamp (voxel diagonals)
    uint splat_vpl;      // VPL_SPLAT: the index in the row this pass adds
} pc;

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
#include "vpl_gather.glsl"

void main() {
    uvec2 pattern = max(pc.pattern.xy, uvec2(1u));
    ivec2 size = ivec2(frame.counts.zw);
    uvec2 block = (uvec2(size) + pattern - 1u) / pattern;
    uvec2 gid = gl_GlobalInvocationID.xy;
    uvec2 cell = gid / block;     // the block (i, j): which set
    uvec2 within = gid % block;   // position inside the block
    if (any(greaterThanEqual(cell, pattern))) return;
    ivec2 px = ivec2(within * pattern + cell);
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
    vec3 to_eye = toward_camera(frame.camera_position, frame.camera_forward, p);
    // GGX receivers: F0 in the lobe target, the roughness in the normal's w, the diffuse
    // color (1 - m) b in the albedo; r >= 0.01 keeps D finite (as for senders, vpl.glsl).
    vec4 lobe_texel = HAS_GGX ? texelFetch(gb_specular, px, 0) : vec4(0.0);
    bool ggx = HAS_GGX && lobe_texel.a > 1.5;
    vec3 diffuse = ggx ? texelFetch(gb_albedo, px, 0).rgb : vec3(0.0);
    float roughness = max(ns.w, max(MIN_ROUGHNESS, 0.01));
    float shininess = MIN_ROUGHNESS > 0.0 ? min(ns.w, 2.0 / pow(MIN_ROUGHNESS, 4.0) - 2.0) : ns.w;
    uint row = pc.pattern.z;
    uint first = (cell.y * pattern.x + cell.x) * row;
    vec3 e = vec3(0.0);
    vec3 lobe = vec3(0.0);
#ifdef VPL_SPLAT
    uint begin = pc.splat_vpl;
    uint end = min(begin + 1u, row);
#else
    uint begin = 0u;
    uint end = row;
#endif
    GpuVplGatherPush g = GpuVplGatherPush(pc.world_to_voxel, pc.dims, pc.pattern, pc.trace,
                                          pc.d_min_m2, pc.voxel_diagonal_m, pc.offsets, pc.splat_vpl);
    for (uint i = begin; i < end; ++i) {
        // I cos theta_P / (d_min + d^2) with I = I_max cos theta_VPL (plus a glossy sender's
        // lobe), where the VPL lights p (vpl_gather.glsl).
        vec3 dir, arriving;
        if (!vpl_arriving(g, vpls[first + i], p, n, dir, arriving)) continue;
        e += arriving;
        if (ggx) lobe += brdf_ggx(diffuse, lobe_texel.rgb, roughness, n, dir, to_eye) * arriving;
        else if (phong) lobe += brdf_phong(specular, shininess, n, dir, to_eye) * arriving;
    }
    vec3 result = e;
    if (ggx) result = lobe;
    else if (phong) result = texelFetch(gb_albedo, px, 0).rgb / PI * e + lobe;
#ifdef VPL_SPLAT
    if (pc.splat_vpl > 0u) result += imageLoad(irradiance, px).rgb;
#endif
    imageStore(irradiance, px, vec4(result, 1.0));
}

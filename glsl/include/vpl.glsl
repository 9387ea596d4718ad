// Virtual point lights (Thiedemann 2010, Ch. 7): the VPL record, its buffer layout and the
// generation push constants shared by gi_vpl_generate.comp and gi_vpl_bounce.comp.
//
// The buffer holds one row per interleaving set (§7.3.2); row s holds bounces x lights x K
// VPLs, K per light and set: index = s * R + (bounce * lights + light) * K + k, with
// R = bounces * lights * K + S, then S source VPLs (K points on emissive surfaces in scenes
// that have them, else none). The lights are those with reflective maps, then one slot for
// the emitters (emissive surfaces and area lights) when the scene has any. Each row is a
// complete estimator of the indirect light on its own.
#ifndef VPL_GLSL
#define VPL_GLSL

#include "brdf.glsl"

// Mirrors `GpuVpl` in src/gi/vpl.rs.
struct GpuVpl {
    vec4 position;  // xyz world position (m); w 1 valid, 0 invalid (the sample hit nothing)
    vec4 normal;    // xyz unit normal of the sending surface, facing where it sends light
    vec4 flux;      // rgb the diffuse part's flux Phi_VPL (W); w the bounce (0: first)
    vec4 lobe;      // glossy senders: xyz unit direction wi toward the incident light,
                    // w the Phong exponent or the GGX roughness r
    vec4 specular;  // glossy senders: rgb Phong rho_s or GGX F0; w the lobe kind
                    // (LOBE_PHONG 1, LOBE_GGX 2; 0 for Lambert senders)
    vec4 incident;  // glossy senders: rgb the incident flux Phi_in (W); 0 else
};

// A glossy VPL stands for a small surface element dA that receives the flux Phi_in = E dA
// from direction wi (thesis §7.3, with a BRDF f instead of the Phong lobe alone): it reflects
// the radiance L(w) = f(wi, w) E, so its intensity is I(w) = L(w) cos theta dA =
// f(wi, w) Phi_in cos theta. Lambert senders keep Phi_VPL = rho Phi_in, I = Phi_VPL / pi cos.
// The diffuse part of a Phong sender is Phi_VPL = rho_d Phi_in; of a GGX sender
// Phi_VPL = (1 - m) b (1 - F_d(n.wi)) Phi_in, whose factor (1 - F_d(n.w)) toward w is
// applied here (brdf.glsl's brdf_ggx split at its two lobes).
const float VPL_LOBE_PHONG = 1.0;
const float VPL_LOBE_GGX = 2.0;

bool vpl_ggx(GpuVpl v) {
    return v.specular.w > 1.5;
}

bool vpl_phong(GpuVpl v) {
    return v.specular.w > 0.5 && v.specular.w < 1.5;
}

// Intensity of a VPL toward unit direction `w` leaving it (W/sr): Phi_VPL / pi cos theta for
// Lambert senders, f(wi, w) Phi_in cos theta for glossy ones (above).
vec3 vpl_intensity(GpuVpl v, vec3 w) {
    float c = max(dot(v.normal.xyz, w), 0.0);
    vec3 i = v.flux.rgb * (c / 3.14159265358979323846);
    if (vpl_phong(v)) {
        i += brdf_phong(v.specular.rgb, v.lobe.w, v.normal.xyz, v.lobe.xyz, w) * v.incident.rgb * c;
    } else if (vpl_ggx(v)) {
        i = i * ggx_diffuse_weight(c)
            + brdf_ggx_specular(v.specular.rgb, v.lobe.w, v.normal.xyz, v.lobe.xyz, w) * v.incident.rgb * c;
    }
    return i;
}

// Mirrors `GpuVplGeneratePush` in src/gi/gi_common.rs.
#ifdef VPL_GENERATE_PUSH
layout(push_constant) uniform VplGeneratePush {
    mat4 world_to_voxel;
    ivec4 dims;     // voxels x, y, depth; w max hierarchy level
    uvec4 counts;   // x sets, y lights, z VPLs per set and light (K), w bounces
    uvec4 trace;    // x start level, y max iterations, z this pass's bounce, w shadow-map resolution
    vec4 params;    // x normal offset (voxel diagonals), y voxel diagonal (m), z ray length (m), w halton_point's frames
} pc;

// The Halton index of VPL kk of set `set_` this frame. Each set owns a block of T K points
// (index 0, the origin, skipped), T the history's frames under temporal accumulation
// (gi.temporal) and 1 without, and frame f (modulo T) takes its K points f K .. f K + K - 1:
// N frames of K points are the block's first N K, the points one frame of N K VPLs per set
// would take from a block of its own. params.w's bits hold T << 16 | f.
uint halton_point(uint set_, uint kk) {
    uint packed = floatBitsToUint(pc.params.w);
    uint k = max(pc.counts.z, 1u);
    return set_ * k * max(packed >> 16u, 1u) + (packed & 0xffffu) * k + kk + 1u;
}

// Emitter VPLs at the end of each row (gi_vpl_emit.comp): K in scenes with emissive surfaces,
// 0 otherwise (a specialization constant of every pass that indexes the buffer this way).
layout(constant_id = 2) const uint SOURCE_VPLS = 0u;

uint vpl_index(uint set_, uint bounce, uint light, uint k) {
    uint row = pc.counts.w * pc.counts.y * pc.counts.z + SOURCE_VPLS;
    return set_ * row + (bounce * pc.counts.y + light) * pc.counts.z + k;
}

// Index of source VPL k of set `set_` (the emitter point itself, gi_vpl_emit.comp).
uint source_vpl_index(uint set_, uint k) {
    uint row = pc.counts.w * pc.counts.y * pc.counts.z + SOURCE_VPLS;
    return set_ * row + pc.counts.w * pc.counts.y * pc.counts.z + k;
}
#endif

#ifdef VPL_HIT
// The passes that end a ray at a voxel hit (gi_vpl_emit.comp, gi_vpl_bounce.comp): with Phong
// or GGX materials (HAS_LOBES) the hit's material comes from the material volume
// (material_lobe.glsl's voxel_lobe); without, every hit is Lambert with the albedo volume's
// color. Needs gi_common.glsl and material_lobe.glsl.

// The VPL at voxel hit p (normal hn, facing the ray's origin) of a ray along d carrying the
// flux phi (W): a Lambert surface reflects Phi_VPL = phi rho; a glossy one keeps phi as its
// incident flux Phi_in from wi = -d and its diffuse part as Phi_VPL (above). The GGX roughness
// is kept at r >= 0.01 (alpha >= 1e-4, material_lobe.glsl's lobe_alpha), where D stays finite.
GpuVpl hit_vpl(vec3 p, vec3 hn, vec3 d, vec3 phi, Lobe m, float bounce) {
    if (m.kind == LOBE_LAMBERT) {
        return GpuVpl(vec4(p, 1.0), vec4(hn, 0.0), vec4(phi * m.diffuse, bounce), vec4(0.0), vec4(0.0), vec4(0.0));
    }
    vec3 wi = -d;
    vec3 diffuse = phi * m.diffuse;
    float param = m.param;
    if (m.kind == LOBE_GGX) {
        diffuse *= ggx_diffuse_weight(dot(hn, wi));
        param = sqrt(lobe_alpha(m));
    }
    return GpuVpl(vec4(p, 1.0), vec4(hn, 0.0), vec4(diffuse, bounce), vec4(wi, param), vec4(m.specular, float(m.kind)), vec4(phi, 0.0));
}
#endif

// Radical inverse of i in base b (Halton 1964): the digits of i mirrored at the point.
float halton(uint i, uint b) {
    float f = 1.0;
    float r = 0.0;
    float inv = 1.0 / float(b);
    while (i > 0u) {
        f *= inv;
        r += f * float(i % b);
        i /= b;
    }
    return r;
}

#endif

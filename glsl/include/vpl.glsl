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

// Mirrors `GpuVpl` in src/gi/vpl.rs.
struct GpuVpl {
    vec4 position;  // xyz world position (m); w 1 valid, 0 invalid (the sample hit nothing)
    vec4 normal;    // xyz unit normal of the sending surface, facing where it sends light
    vec4 flux;      // rgb diffusely reflected flux Phi_VPL (W); w the bounce (0: first)
    vec4 lobe;      // Phong senders: xyz the mirror direction of the incident light, w shininess
    vec4 specular;  // Phong senders: rgb rho_s * Phi_in (W), Phi_in the incident flux; 0 else
};

// Intensity of a VPL toward unit direction `w` leaving it (W/sr): the Lambert part
// Phi / pi cos theta plus, for Phong senders, rho_s Phi_in (n + 2) / (2 pi) cos^n(alpha) cos theta
// (normalized Phong, alpha the angle between w and the mirror direction; thesis §7.3).
vec3 vpl_intensity(GpuVpl v, vec3 w) {
    float c = max(dot(v.normal.xyz, w), 0.0);
    vec3 i = v.flux.rgb * (c / 3.14159265358979323846);
    if (v.lobe.w > 0.0) {
        float ca = max(dot(v.lobe.xyz, w), 0.0);
        i += v.specular.rgb * ((v.lobe.w + 2.0) / (2.0 * 3.14159265358979323846) * pow(ca, v.lobe.w) * c);
    }
    return i;
}

// Mirrors `GpuVplGeneratePush` in src/gi/vpl.rs.
#ifdef VPL_GENERATE_PUSH
layout(push_constant) uniform VplGeneratePush {
    mat4 world_to_voxel;
    ivec4 dims;     // voxels x, y, depth; w max hierarchy level
    uvec4 counts;   // x sets, y lights, z VPLs per set and light (K), w bounces
    uvec4 trace;    // x start level, y max iterations, z this pass's bounce, w shadow-map resolution
    vec4 params;    // x normal offset (voxel diagonals), y voxel diagonal (m), z ray length (m), w unused
} pc;

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

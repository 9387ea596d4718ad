// The per-VPL term of the VPL gather (Thiedemann 2010, §7.3), shared by the G-buffer's pixels
// (gi_vpl_gather_body.glsl) and the transparent layers' fragments (oit_gather_vpl.frag): a VPL
// of intensity I(w) gives a receiver point E = I(w) cos theta_P / (d_min + d^2), times the
// visibility of the segment between them by the voxel ray test (offsets at both ends,
// §5.3.1), or 1 without visibility. Needs vpl.glsl and voxel_traverse.glsl (whose accessors the
// including shader defines first).
#ifndef VPL_GATHER_GLSL
#define VPL_GATHER_GLSL

// Mirrors `GpuVplGatherPush` in src/gi/vpl.rs: gi_vpl_gather's push constants (the pass makes
// one of these from its push block) and the contents of oit_gather_vpl's parameter buffer.
struct GpuVplGatherPush {
    mat4 world_to_voxel;
    ivec4 dims;          // voxels x, y, depth; w max hierarchy level
    uvec4 pattern;       // x N, y M, z VPLs per row, w visibility (1: voxel test, 0: none)
    uvec2 trace;         // x start level, y max iterations
    float d_min_m2;      // d_min of E = I cos cos / (d_min + d^2), m^2
    float voxel_diagonal_m;
    vec3 offsets;        // x normal offset, y ray offset k2, z its clamp (voxel diagonals)
    uint splat_vpl;      // gi_vpl_splat: the index in the row the pass adds
};

// Whether the segment from receiver p (normal n) to the VPL at q (normal m) is free, both ends
// moved off their surfaces along the normal by k1 and along the segment by
// min(k2 h / cos, clamp) (thesis §5.3.1, as the hemisphere rays do at their origin).
bool vpl_segment_visible(GpuVplGatherPush g, vec3 p, vec3 n, vec3 q, vec3 m, vec3 dir, float cos_p, float cos_v) {
    float h = g.voxel_diagonal_m;
    float along_p = min(g.offsets.y * h / max(cos_p, 1e-4), g.offsets.z * h);
    float along_v = min(g.offsets.y * h / max(cos_v, 1e-4), g.offsets.z * h);
    vec3 a = p + n * (g.offsets.x * h) + dir * along_p;
    vec3 b = q + m * (g.offsets.x * h) - dir * along_v;
    // The offsets passed each other: the two points are closer than the voxels resolve.
    if (dot(b - a, dir) <= 0.0) return true;
    vec3 av = (g.world_to_voxel * vec4(a, 1.0)).xyz;
    vec3 bv = (g.world_to_voxel * vec4(b, 1.0)).xyz;
    return voxel_visible(g.dims.xyz, uint(g.dims.w), av, bv, g.trace.x, g.trace.y);
}

// Whether `vpl` lights the receiver point p (unit normal n, the side it receives on): valid,
// in front of the receiver, facing it, and (with visibility on) seen. Then `arriving` is its
// irradiance I(w) cos theta_P / (d_min + d^2) at p, with I = I_max cos theta_VPL (plus a glossy
// sender's lobe, vpl_intensity), and `dir` the unit direction from p toward it.
bool vpl_arriving(GpuVplGatherPush g, GpuVpl vpl, vec3 p, vec3 n, out vec3 dir, out vec3 arriving) {
    dir = vec3(0.0);
    arriving = vec3(0.0);
    if (vpl.position.w == 0.0) return false;  // invalid: carries no flux
    vec3 to_vpl = vpl.position.xyz - p;
    float d2 = dot(to_vpl, to_vpl);
    if (d2 <= 0.0) return false;
    dir = to_vpl * inversesqrt(d2);
    float cos_p = dot(n, dir);
    float cos_v = -dot(vpl.normal.xyz, dir);
    if (cos_p <= 0.0 || cos_v <= 0.0) return false;
    if (g.pattern.w != 0u && !vpl_segment_visible(g, p, n, vpl.position.xyz, vpl.normal.xyz, dir, cos_p, cos_v)) return false;
    arriving = vpl_intensity(vpl, -dir) * cos_p / (g.d_min_m2 + d2);
    return true;
}

#endif

#version 450
// Debug views of the voxel grid: camera rays cast through the GPU column image.
// mode 0 (voxels): hierarchical first hit, shaded by the face the ray entered through (N.L);
// mode 1 (steps): hierarchical traversal step count on a heat ramp;
// mode 2 (level): occupancy of hierarchy level `level` (texel x,y blocks of 2^level voxels,
//                 one voxel deep) by an exact walk, shaded like mode 0;
// mode 3 (albedo): hierarchical first hit, the albedo volume's value at the hit voxel (the
//                  color half shaded like mode 0).
// Writes the debug quantity (shade, steps, occupancy or albedo) to `value` and its color to
// `color`.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform usampler2DArray columns;  // all mips: the OR hierarchy
layout(set = 0, binding = 1, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D value;
layout(set = 0, binding = 3, rgba8) uniform writeonly image2D color;
// Congruent with the bits (x, y, depth k); a placeholder outside mode 3.
layout(set = 0, binding = 4) uniform sampler3D albedo_volume;

layout(push_constant) uniform Push {
    mat4 ndc_to_voxel;  // Vulkan NDC (z 0 near, 1 far) -> continuous voxel coordinates
    ivec4 dims;         // xyz voxels, w coarsest level
    uint mode;          // the view (DebugView::shader_mode)
    uint level;         // the hierarchy level the level view shows
    uint max_iterations;
    uint start_level;
    vec4 light;         // xyz unit light direction in voxel axes, w steps at the ramp's top
} pc;

// Level whose occupancy vx_voxel reports (0 except in the level view).
uint g_level = 0u;

uvec4 vx_column(uint level, int x, int y, uint layer) {
    return texelFetch(columns, ivec3(x, y, int(layer)), int(level));
}

uvec4 vx_ray_mask(uint a, uint b) {
    return ray_masks[b * 128u + a];
}

bool vx_voxel(int x, int y, int k) {
    uvec4 c = vx_column(g_level, x >> g_level, y >> g_level, uint(k) / 128u);
    uint bit = uint(k) % 128u;
    return ((c[bit / 32u] >> (bit % 32u)) & 1u) != 0u;
}

#include "voxel_traverse.glsl"

// Black -> red -> yellow -> white over [0, 1].
vec3 heat(float x) {
    return clamp(vec3(3.0 * x, 3.0 * x - 1.0, 3.0 * x - 2.0), 0.0, 1.0);
}

// N.L shade of the face through which the ray o + t*d (voxel space) entered voxel v at t,
// darkened near the face's edges (cells of `cell` voxels in x and y) so voxels stand apart.
float face_shade(vec3 o, vec3 d, uvec3 v, float t, float cell) {
    int axis = 0;
    float t_enter = -VX_INF;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0) continue;
        float b = d[i] > 0.0 ? float(v[i]) : float(v[i]) + 1.0;
        float te = (b - o[i]) / d[i];
        if (te > t_enter) {
            t_enter = te;
            axis = i;
        }
    }
    vec3 n = vec3(0.0);
    n[axis] = d[axis] > 0.0 ? -1.0 : 1.0;
    float shade = 0.15 + 0.85 * max(dot(n, pc.light.xyz), 0.0);
    vec3 p = o + t * d;
    vec3 size = vec3(cell, cell, 1.0);
    float edge = 1.0;
    for (int i = 0; i < 3; ++i) {
        if (i == axis) continue;
        float f = fract(p[i] / size[i]);
        edge = min(edge, min(f, 1.0 - f) * size[i]);
    }
    return shade * mix(0.6, 1.0, smoothstep(0.02, 0.1, edge));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(color);
    if (any(greaterThanEqual(px, size))) {
        return;
    }
    vec2 ndc = (vec2(px) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 a = pc.ndc_to_voxel * vec4(ndc, 0.0, 1.0);
    vec4 b = pc.ndc_to_voxel * vec4(ndc, 1.0, 1.0);
    vec3 o = a.xyz / a.w;
    vec3 d = b.xyz / b.w - o;
    uint mode = pc.mode;
    VxHit h;
    float cell = 1.0;
    if (mode == 2u) {
        g_level = min(pc.level, uint(pc.dims.w));
        cell = float(1 << g_level);
        h = voxel_first_hit_dda(pc.dims.xyz, o, d, 1.0);
    } else {
        h = voxel_first_hit(pc.dims.xyz, uint(pc.dims.w), o, d, 1.0, pc.start_level, pc.max_iterations);
    }
    vec4 v = vec4(0.0, 0.0, 0.0, 1.0);
    vec3 c = vec3(0.0);
    if (mode == 1u) {
        float steps = float(h.steps);
        v = vec4(steps, h.hit ? 1.0 : 0.0, h.ran_out ? 1.0 : 0.0, 1.0);
        c = heat(steps / max(pc.light.w, 1.0));
    } else if (mode == 3u) {
        if (h.hit) {
            vec3 albedo = texelFetch(albedo_volume, ivec3(h.voxel), 0).rgb;
            v = vec4(albedo, 1.0);
            // Half shaded like mode 0, in the picture only: same-colored surfaces separate,
            // and walls facing away from the light keep their color.
            c = albedo * (0.5 + 0.5 * face_shade(o, d, h.voxel, h.t, 1.0));
        }
    } else if (h.hit) {
        float s = face_shade(o, d, h.voxel, h.t, cell);
        v = vec4(vec3(s), 1.0);
        // Level view: a tint per level so screenshots say which level they show.
        c = mode == 2u ? s * mix(vec3(1.0), vec3(0.55, 0.8, 1.0), min(float(g_level), 1.0)) : vec3(s);
    }
    imageStore(value, px, v);
    imageStore(color, px, vec4(c, 1.0));
}

#version 450
// Casts a batch of voxel-space rays through a binary voxel hierarchy held in storage buffers:
// the GPU side of the CPU-twin tests and of `voxgi bench traverse`.
// mode 0: hierarchical first hit, 1: DDA, 2: 1-bit marching, 3: 3-bit marching.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Columns { uvec4 columns[]; };
layout(set = 0, binding = 1, std430) readonly buffer Levels { uvec4 levels[]; };  // x offset, y width, z height
layout(set = 0, binding = 2, std430) readonly buffer RayMasks { uvec4 ray_masks[]; };
struct Ray { vec4 origin_tmax; vec4 dir; };
layout(set = 0, binding = 3, std430) readonly buffer Rays { Ray rays[]; };
struct Result { uvec4 hit_voxel; vec4 t_steps; };  // (hit, x, y, k), (t, steps, ran_out, 0)
layout(set = 0, binding = 4, std430) writeonly buffer Results { Result results[]; };

layout(push_constant) uniform Push {
    ivec4 dims;             // xyz voxels, w max level
    uint start_level;       // hierarchical traversal: the level it starts at
    uint max_iterations;    // hierarchical traversal: its iteration cap
    uint mode;              // 0 hierarchical, 1 exact DDA, 2 1-bit march, 3 3-bit march
    uint ray_count;
    uint marching_samples;  // marching: samples along the ray
} pc;

uvec4 vx_column(uint level, int x, int y, uint layer) {
    uvec4 l = levels[level];
    return columns[l.x + (layer * l.z + uint(y)) * l.y + uint(x)];
}

uvec4 vx_ray_mask(uint a, uint b) {
    return ray_masks[b * 128u + a];
}

bool vx_voxel(int x, int y, int k) {
    uvec4 c = vx_column(0u, x, y, uint(k) / 128u);
    uint bit = uint(k) % 128u;
    return ((c[bit / 32u] >> (bit % 32u)) & 1u) != 0u;
}

#include "voxel_traverse.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.ray_count) return;
    Ray r = rays[i];
    VxHit h;
    uint mode = pc.mode;
    if (mode == 0u) h = voxel_first_hit(pc.dims.xyz, uint(pc.dims.w), r.origin_tmax.xyz, r.dir.xyz, r.origin_tmax.w, pc.start_level, pc.max_iterations);
    else if (mode == 1u) h = voxel_first_hit_dda(pc.dims.xyz, r.origin_tmax.xyz, r.dir.xyz, r.origin_tmax.w);
    else h = voxel_march(pc.dims.xyz, r.origin_tmax.xyz, r.dir.xyz, r.origin_tmax.w, pc.marching_samples, mode == 3u);
    results[i] = Result(uvec4(h.hit ? 1u : 0u, h.voxel), vec4(h.t, float(h.steps), h.ran_out ? 1.0 : 0.0, 0.0));
}

#version 450
// Conservative surface voxelization by the exact triangle/box overlap test (Akenine-Möller
// 2001, "Fast 3D triangle-box overlap testing", separating-axis test), bit for bit the CPU
// reference src/voxel/voxelize.rs: every voxel whose closed box the triangle touches is set.
//
// Exactness: the f32 operations are those of the reference in the same order. Every value
// that mixes products and sums is `precise`, so no fused multiply-add is contracted (Vulkan
// guarantees correctly rounded +, -, *; division and sqrt only bound the per-column depth
// range, widened by a voxel, and never decide a bit).
//
// One workgroup per triangle (times the dispatch's z splits for large triangles); its
// invocations share out the columns of the triangle's voxel bounding box, and each walks its
// column's depth range, ORing whole words.
#include "voxel_bits.glsl"

// Invocations per triangle (specialization constant; VoxelPipelines picks it).
layout(local_size_x_id = 0) in;

struct Triangle {
    // World-space vertices; v[0].w = 1 - opacity, v[1].w = the object's coverage seed
    // (voxel_coverage.glsl), v[2].w unused.
    vec4 v[3];
};
layout(set = 0, binding = 0, std430) readonly buffer Triangles { Triangle tris[]; };
layout(set = 0, binding = 1, std430) buffer Columns { uint words[]; };

layout(push_constant) uniform Push {
    vec4 grid_min;   // world corner of the grid box (xyz)
    vec4 scale;      // voxels per meter in the voxel-camera frame (u, v, w)
    uvec4 dims;      // res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)
    uvec4 extent;    // column-buffer width, height; triangle count; first triangle
} pc;

#define VOXEL_COLUMN_BEGIN(x, y) uint word = 0xffffffffu; uint bits = 0u;
#define VOXEL_HIT(x, y, k)                                              \
    {                                                                   \
        uint wi = voxel_word_index(uvec2(x, y), k, pc.extent.xy);       \
        if (wi != word) {                                               \
            if (bits != 0u) atomicOr(words[word], bits);                \
            word = wi;                                                  \
            bits = 0u;                                                  \
        }                                                               \
        bits |= 1u << voxel_bit(k);                                     \
    }
#define VOXEL_COLUMN_END(x, y) if (bits != 0u) atomicOr(words[word], bits);
#define VOXEL_COVERAGE(t) vec2(t.v[0].w, t.v[1].w)
#include "voxelize_core.glsl"

void main() {
    voxelize_triangle_core();
}

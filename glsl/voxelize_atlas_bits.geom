#version 450
// Routes each point to the array layer of its 128-voxel depth chunk (layer = k / 128, the bit
// convention of voxel_bits.glsl): the thesis's single RGBA32UI target holds one chunk; grids
// deeper than 128 need one layer per chunk.
#include "voxel_bits.glsl"

layout(points) in;
layout(points, max_vertices = 1) out;

layout(location = 0) flat in int v_depth[];
layout(location = 0) flat out uint g_depth;

void main() {
    if (v_depth[0] < 0) {
        return;
    }
    gl_Position = gl_in[0].gl_Position;
    gl_Layer = int(voxel_layer(uint(v_depth[0])));
    g_depth = uint(v_depth[0]);
    EmitVertex();
    EndPrimitive();
}

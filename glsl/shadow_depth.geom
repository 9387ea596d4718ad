#version 450
// Shadow maps: every shadow view (spot map, directional map, each cube face of a point light)
// is one layer of a single depth array; the geometry shader routes triangles to their layer.
#include "frame.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
} pc;

void main() {
    mat4 vp = frame.shadow_views[pc.view].view_proj;
    for (int i = 0; i < 3; ++i) {
        gl_Position = vp * gl_in[i].gl_Position;
        gl_Layer = int(pc.view);
        EmitVertex();
    }
    EndPrimitive();
}

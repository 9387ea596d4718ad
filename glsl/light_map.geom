#version 450
// Reflective light maps: route each triangle to the layer of the light view being drawn
// (the same views as the shadow maps, at the light maps' own resolution).
#include "frame.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
} pc;

layout(location = 0) in vec3 in_normal[];
layout(location = 0) out vec3 out_normal;
layout(location = 1) out vec3 out_world;

void main() {
    mat4 vp = frame.shadow_views[pc.view].view_proj;
    for (int i = 0; i < 3; ++i) {
        gl_Position = vp * gl_in[i].gl_Position;
        gl_Layer = int(pc.view);
        out_normal = in_normal[i];
        out_world = gl_in[i].gl_Position.xyz;
        EmitVertex();
    }
    EndPrimitive();
}

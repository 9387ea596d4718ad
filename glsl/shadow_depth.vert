#version 450
// Shadow maps: world position of each vertex; the geometry shader projects it into the layer
// of the shadow view being drawn.
layout(location = 0) in vec3 in_position;

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

void main() {
    gl_Position = pc.model * vec4(in_position, 1.0);
}

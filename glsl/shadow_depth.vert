#version 450
// Shadow maps: world position of each vertex; the geometry shader projects it into the layer
// of the shadow view being drawn.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

// Texture coordinates (OBJ's v up), read by the fragment shaders only in scenes with alpha
// maps (alpha_map.glsl).
layout(location = 0) out vec2 out_tex_uv;

void main() {
    gl_Position = pc.model * vec4(in_position, 1.0);
    out_tex_uv = in_uv;
}

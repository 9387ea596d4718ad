#version 450
// Reflective light maps (Thiedemann 2010, §6.3.3: spot and cube maps): world position and normal of each vertex; the geometry
// shader projects into the light view's layer.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

layout(location = 0) out vec3 out_normal;
// Texture coordinates (OBJ's v up), read by light_map.frag only in scenes with its maps.
layout(location = 1) out vec2 out_uv;

void main() {
    gl_Position = pc.model * vec4(in_position, 1.0);
    out_normal = transpose(inverse(mat3(pc.model))) * in_normal;
    out_uv = in_uv;
}

#version 450
// Object picking: the drawn object's index + 1 (0 where nothing was drawn).

layout(push_constant) uniform Push {
    mat4 model;
    vec4 pixel;
    uint object;
} pc;

layout(location = 0) out uint out_object;

void main() {
    out_object = pc.object;
}

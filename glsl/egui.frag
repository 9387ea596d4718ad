#version 450
// egui's font atlas holds sRGB-encoded premultiplied RGBA in a UNORM image.
layout(set = 0, binding = 0) uniform sampler2D atlas;

layout(location = 0) in vec2 v_uv;
layout(location = 1) in vec4 v_color;
layout(location = 0) out vec4 color;

void main() {
    color = v_color * texture(atlas, v_uv);
}

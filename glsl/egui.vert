#version 450
// The viewer's UI (egui): positions in points, top-left origin; colors are sRGB-encoded and
// premultiplied, and stay so: the swapchain is UNORM, so blending happens in gamma space as
// egui's own painters do on such targets.
layout(location = 0) in vec2 pos_points;
layout(location = 1) in vec2 uv;
layout(location = 2) in vec4 color;

layout(push_constant) uniform Push {
    vec2 screen_size_points;
} pc;

layout(location = 0) out vec2 v_uv;
layout(location = 1) out vec4 v_color;

void main() {
    // Vulkan clip space has y down, like egui's points.
    gl_Position = vec4(2.0 * pos_points / pc.screen_size_points - 1.0, 0.0, 1.0);
    v_uv = uv;
    v_color = color;
}

#version 450
// Object picking (the viewer, src/app/pick.rs): the camera's view drawn into a 1x1 target
// that covers exactly the clicked pixel, so the depth test leaves the nearest surface there.
#include "frame.glsl"

layout(location = 0) in vec3 in_position;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    // xy: the clicked pixel's centre in NDC; zw: the frame's size in pixels. With
    // clip' = (clip - c * clip.w) * size, the pixel's footprint (2/size wide in NDC) fills
    // [-1, 1]: a pick matrix (gluPickMatrix) for one pixel.
    vec4 pixel;
    uint object;
} pc;

void main() {
    vec4 clip = frame.view_proj * (pc.model * vec4(in_position, 1.0));
    clip.xy = (clip.xy - pc.pixel.xy * clip.w) * pc.pixel.zw;
    gl_Position = clip;
}

// G-buffer pass: world-space normals and material ids of every visible surface (the body of
// gbuffer.vert and, with MULTIVIEW, gbuffer_multiview.vert).
#include "frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#ifdef MULTIVIEW
// Both eyes in one draw (gbuffer_multiview.vert): view 0 is the left eye (`frame`), view 1
// the right eye; each view draws into its layer of the two-layer targets.
layout(set = 0, binding = 8, std430) readonly buffer FrameRightBuf { GpuFrame frame_right; };
#define EYE_CLIP(world) ((gl_ViewIndex == 0 ? frame.view_proj : frame_right.view_proj) * (world))
// Drivers that draw view 1's clipped triangles into layer 0 (Mesa's draw module before
// 23.0.4: `render::stereo::MultiviewDefect`) draw every mesh with two instances: instance 0
// puts all its vertices on one point inside the clip volume (nothing to clip, zero area, no
// fragment), so the draw module emits it directly, which flushes the batch of clipped
// triangles the previous view left open; instance 1 is the mesh.
layout(constant_id = 8) const bool FLUSH_INSTANCE = false;
#else
#define EYE_CLIP(world) (frame.view_proj * (world))
#endif

layout(push_constant) uniform Push {
    mat4 model;
    uint material;
    // Rows of prev_model · model⁻¹ (the draw's world motion since the previous frame; a
    // row vector times it gives the point's previous world position): gbuffer.frag's motion
    // vectors only.
    mat3x4 motion;
} pc;

layout(location = 0) out vec3 out_normal;
layout(location = 1) out vec2 out_uv;
layout(location = 2) out vec3 out_world;

void main() {
#ifdef MULTIVIEW
    if (FLUSH_INSTANCE && gl_InstanceIndex == 0) {
        out_normal = vec3(0.0);
        out_uv = vec2(0.0);
        out_world = vec3(0.0);
        gl_Position = vec4(0.0, 0.0, 0.5, 1.0);
        return;
    }
#endif
    vec4 world = pc.model * vec4(in_position, 1.0);
    out_normal = transpose(inverse(mat3(pc.model))) * in_normal;
    out_uv = in_uv;
    out_world = world.xyz;
    gl_Position = EYE_CLIP(world);
}

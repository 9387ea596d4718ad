#version 450
// The SAO depth pyramid (McGuire, Mara and Luebke 2012 §3.1, "scalable": far taps read
// coarser levels, so the taps of a pixel stay within a few cache lines at any radius; Oetke
// 2017 §2.5 mips normals too). Per texel the view depth z (meters along the camera axis; 0:
// sky) in w and the world normal in xyz, of one full-resolution pixel:
// - FIRST: level 0 at the frame's size, from the G-buffer's depth and normal;
// - otherwise level k from level k − 1 by McGuire et al.'s rotated-grid subsample: texel q
//   keeps child 2q + ((q.y & 1) ^ 1, (q.x & 1) ^ 1) (clamped to the finer level), so the
//   kept children alternate over the 2x2 blocks instead of always being the same corner,
//   and every level's value is an actual surface point of the frame, never a blend of two
//   depths.
#include "frame.glsl"

layout(constant_id = 0) const bool FIRST = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_depth;    // FIRST
layout(set = 0, binding = 2) uniform sampler2D gb_normal;   // FIRST
layout(set = 0, binding = 3) uniform sampler2D finer;       // !FIRST: level k − 1
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D dst;

// The camera's unit view direction, from the clip-space z axis.
vec3 camera_forward() {
    vec4 a = frame.inv_view_proj * vec4(0.0, 0.0, 0.0, 1.0);
    vec4 b = frame.inv_view_proj * vec4(0.0, 0.0, 1.0, 1.0);
    return normalize(b.xyz / b.w - a.xyz / a.w);
}

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, imageSize(dst)))) return;
    if (FIRST) {
        float depth = texelFetch(gb_depth, q, 0).r;
        if (depth >= 1.0) {
            imageStore(dst, q, vec4(0.0));
            return;
        }
        ivec2 size = ivec2(frame.counts.zw);
        vec3 p = pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, q, vec2(size), depth);
        float z = max(dot(p - frame.camera_position.xyz, camera_forward()), 1e-6);
        imageStore(dst, q, vec4(normalize(texelFetch(gb_normal, q, 0).xyz), z));
        return;
    }
    ivec2 child = min(2 * q + ivec2((q.y & 1) ^ 1, (q.x & 1) ^ 1), textureSize(finer, 0) - 1);
    imageStore(dst, q, texelFetch(finer, child, 0));
}

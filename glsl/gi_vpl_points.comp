#version 450
// Debug view of the VPLs (`--vpl-show`): every valid VPL of every set drawn as a 3x3-pixel dot
// over the lit image, unless the G-buffer shows a nearer surface there (1% of the distance
// tolerance); first-bounce VPLs yellow, later bounces cyan.
#define GI_OWN_PUSH
#include "frame.glsl"
#include "vpl.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_depth;
layout(set = 0, binding = 2, std430) readonly buffer Vpls { GpuVpl vpls[]; };
layout(set = 0, binding = 3, rgba32f) uniform image2D radiance;

// Mirrors `GpuVplPointsPush` in src/gi/vpl.rs.
layout(push_constant) uniform VplPointsPush {
    uint count;        // VPLs in the buffer
    float radiance_w;  // the dots' radiance, W/(m^2 sr)
} pc;

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, depth);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    GpuVpl v = vpls[i];
    if (v.position.w == 0.0) return;
    vec4 c = frame.view_proj * vec4(v.position.xyz, 1.0);
    if (c.w <= 0.0) return;
    // Orthographic: w is 1 everywhere; a VPL behind the camera's plane (clip z < 0) is unseen.
    if (frame_orthographic(frame.camera_forward) && c.z < 0.0) return;
    vec2 size = vec2(frame.counts.zw);
    ivec2 center = ivec2(floor((c.xy / c.w * 0.5 + 0.5) * size));
    float d_vpl = camera_distance(frame.camera_position, frame.camera_forward, v.position.xyz);
    vec3 color = (v.flux.w == 0.0 ? vec3(1.0, 1.0, 0.0) : vec3(0.0, 1.0, 1.0)) * pc.radiance_w;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            ivec2 px = center + ivec2(x, y);
            if (any(lessThan(px, ivec2(0))) || any(greaterThanEqual(px, ivec2(size)))) continue;
            bool sky = texelFetch(gb_depth, px, 0).r >= 1.0;
            float d_surface = sky ? 1e30 : camera_distance(frame.camera_position, frame.camera_forward, world_at(px, size));
            if (d_vpl <= d_surface * 1.01) imageStore(radiance, px, vec4(color, 1.0));
        }
    }
}

#version 450
// Starts a frame's transparency lists: every head pointer ~0u (an empty list) and the node
// counter 0, with the node buffer's capacity for oit_gather.frag to test against.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, r32ui) uniform writeonly uimage2D heads;
// x nodes requested, y capacity, z pixels with more layers than K, w layers dropped there.
layout(set = 0, binding = 1, std430) writeonly buffer Counters { uvec4 counters; };

layout(push_constant) uniform Push {
    uint capacity;
} pc;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px == ivec2(0)) counters = uvec4(0u, pc.capacity, 0u, 0u);
    if (any(greaterThanEqual(px, imageSize(heads)))) return;
    imageStore(heads, px, uvec4(0xffffffffu));
}

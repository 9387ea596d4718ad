#version 450
// Resolves the transparency lists of oit_gather.frag: per pixel, the K nearest layers are kept
// sorted by depth (insertion sort into a fixed array; a farther layer than all K is dropped),
// then blended back to front over the lit opaque radiance, C = a c + (1 - a) C_behind (the
// "over" operator; Dachsbacher 2014, part 3). Pixels with more than K layers and the layers
// they drop are counted (counters.z, counters.w) for the host to report.
#include "frame.glsl"

layout(constant_id = 0) const uint K = 16u;  // render::oit::MAX_LAYERS

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D heads;
layout(set = 0, binding = 1, std430) readonly buffer Nodes { uvec4 nodes[]; };
layout(set = 0, binding = 2, std430) buffer Counters { uvec4 counters; };
layout(set = 0, binding = 3) uniform sampler2D opaque;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D radiance;
layout(set = 0, binding = 5, std430) readonly buffer FrameBuf { GpuFrame frame; };

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(radiance);
    if (any(greaterThanEqual(px, size))) return;
    float depth[K];
    uint node[K];
    uint count = 0u;
    uint layers = 0u;
    uint capacity = min(counters.x, counters.y);
    uint i = imageLoad(heads, px).x;
    // Each node points at an older one, so the walk ends; the bound is a guard all the same.
    while (i < capacity && layers < capacity) {
        float d = uintBitsToFloat(nodes[i].z);
        layers += 1u;
        if (count < K || d < depth[K - 1u]) {
            uint j = min(count, K - 1u);
            while (j > 0u && depth[j - 1u] > d) {
                depth[j] = depth[j - 1u];
                node[j] = node[j - 1u];
                j -= 1u;
            }
            depth[j] = d;
            node[j] = i;
            count = min(count + 1u, K);
        }
        i = nodes[i].w;
    }
    if (layers > K) {
        atomicAdd(counters.z, 1u);
        atomicAdd(counters.w, layers - K);
    }
    vec4 c = texelFetch(opaque, px, 0);
    for (uint j = count; j > 0u; --j) {
        uvec4 n = nodes[node[j - 1u]];
        vec2 rg = unpackHalf2x16(n.x);
        vec2 ba = unpackHalf2x16(n.y);
        // The layers' colour is half float, pre-exposed by oit_gather.frag (frame.glsl).
        c.rgb = ba.y * (vec3(rg, ba.x) * frame.radiance_scale.y) + (1.0 - ba.y) * c.rgb;
    }
    imageStore(radiance, px, c);
}

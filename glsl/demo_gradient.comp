#version 450
// Demo pass 1: a compute shader writes the test pattern into a storage image.
#include "demo_pattern.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform writeonly image2D dst;

void main() {
    uvec2 size = uvec2(imageSize(dst));
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, size))) return;
    imageStore(dst, ivec2(p), demo_pattern(p, size));
}

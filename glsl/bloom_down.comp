#version 450
// Bloom, down the mip chain: texel (x, y) of level l+1 is the mean of the 2×2 texels
// (2x..2x+1, 2y..2y+1) of level l. The levels' sides are even, so every texel of level l
// lies in exactly one block: radiance times area is conserved level by level.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    ivec2 q = 2 * p;
    vec3 sum = texelFetch(src, q, 0).rgb + texelFetch(src, q + ivec2(1, 0), 0).rgb
        + texelFetch(src, q + ivec2(0, 1), 0).rgb + texelFetch(src, q + ivec2(1, 1), 0).rgb;
    imageStore(dst, p, vec4(0.25 * sum, 1.0));
}

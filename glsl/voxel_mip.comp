#version 450
// One level of the OR hierarchy (Thiedemann 2010, §5.2): texel (x, y) of level l is the OR of texels
// 2x..2x+1, 2y..2y+1 of level l-1, all depth bits kept. Children outside the finer level
// read as empty, matching the CPU BitHierarchy for any size.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform usampler2DArray fine;   // a view of level l-1 only
layout(set = 0, binding = 1, rgba32ui) uniform writeonly uimage2DArray coarse;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec2 size = imageSize(coarse).xy;
    if (any(greaterThanEqual(p.xy, size))) {
        return;
    }
    ivec2 fine_size = textureSize(fine, 0).xy;
    uvec4 c = uvec4(0u);
    for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
            ivec2 q = 2 * p.xy + ivec2(dx, dy);
            if (all(lessThan(q, fine_size))) {
                c |= texelFetch(fine, ivec3(q, p.z), 0);
            }
        }
    }
    imageStore(coarse, p, c);
}

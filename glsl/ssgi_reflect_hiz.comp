#version 450
// One level of the screen-space reflections' two pyramids (Oetke 2017 §5.4), both with a full
// mip chain so the march and the cone lookup read any level of one image:
// - the Hi-Z pyramid: per texel the largest inverse view depth 1/z of the texels it covers,
//   i.e. the nearest surface (0: sky). It must be conservative, which the GI pyramid is not
//   (the voting filter and the fast blit each keep one child's depth, so a thin near surface
//   can vanish from a coarse level and a ray would skip it). 1/z rather than z because it is
//   linear along a ray's screen-space projection (perspective-correct interpolation);
// - the lit-colour pyramid: level 0 the lit colour ssgi_input wrote, each level above the 2x2
//   box average, as the GI pyramid's colour.
// FIRST: level 0 from the GI pyramid's level 0 (position with view depth in w, lit colour);
// otherwise level k from level k − 1 of these pyramids.
// The colour pyramid is half float: level 0 holds the lit colour pre-exposed by the scene's
// 2^-k (frame.glsl's radiance_scale), so that bright emitters and lights stay in range;
// ssgi_reflect.comp multiplies by 2^k. The averages above it are of pre-exposed values.
#include "frame.glsl"

layout(constant_id = 0) const bool FIRST = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D in_depth;   // FIRST: GI position (w: z)
layout(set = 0, binding = 1) uniform sampler2D in_color;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D out_depth;
layout(set = 0, binding = 3, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = 4, std430) readonly buffer FrameBuf { GpuFrame frame; };

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, imageSize(out_depth)))) return;
    if (FIRST) {
        float z = texelFetch(in_depth, q, 0).w;
        imageStore(out_depth, q, vec4(z > 0.0 ? 1.0 / z : 0.0));
        imageStore(out_color, q, vec4(texelFetch(in_color, q, 0).rgb * frame.radiance_scale.x, 1.0));
        return;
    }
    // Mip sizes are halved rounding down: the last texel of an odd-sized level also covers
    // the third child (2q + 2), so that no fine texel is left out of the Hi-Z.
    ivec2 fine = textureSize(in_depth, 0);
    ivec2 last = imageSize(out_depth) - 1;
    ivec2 span = ivec2(2) + ivec2(equal(q, last)) * (fine - 2 * last - 2);
    float nearest = 0.0;
    vec3 color = vec3(0.0);
    for (int y = 0; y < span.y; ++y) {
        for (int x = 0; x < span.x; ++x) {
            ivec2 c = min(2 * q + ivec2(x, y), fine - 1);
            nearest = max(nearest, texelFetch(in_depth, c, 0).r);
            color += texelFetch(in_color, c, 0).rgb;
        }
    }
    imageStore(out_depth, q, vec4(nearest));
    imageStore(out_color, q, vec4(color / float(span.x * span.y), 1.0));
}

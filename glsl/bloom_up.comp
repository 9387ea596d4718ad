#version 450
// Bloom, up the mip chain: dst = base_weight · base + coarse_weight · bilinear(coarse), where
// coarse has half base's size. Bilinear upsampling by 2 (weights 3/4 and 1/4 along each axis,
// clamped at the border) hands each coarse texel's value to the fine texels with weights that
// sum to 4 — the fine texels it covers — so radiance times area is conserved.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D base;
layout(set = 0, binding = 1) uniform sampler2D coarse;
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D dst;

layout(push_constant) uniform Push {
    float base_weight;
    float coarse_weight;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    ivec2 hi = textureSize(coarse, 0) - 1;
    // Fine texel centre p + 0.5 is coarse position (p + 0.5) / 2; texel centres at +0.5.
    vec2 f = (vec2(p) + 0.5) * 0.5 - 0.5;
    ivec2 i0 = ivec2(floor(f));
    vec2 t = f - vec2(i0);
    vec3 a = texelFetch(coarse, clamp(i0, ivec2(0), hi), 0).rgb;
    vec3 b = texelFetch(coarse, clamp(i0 + ivec2(1, 0), ivec2(0), hi), 0).rgb;
    vec3 c = texelFetch(coarse, clamp(i0 + ivec2(0, 1), ivec2(0), hi), 0).rgb;
    vec3 d = texelFetch(coarse, clamp(i0 + ivec2(1, 1), ivec2(0), hi), 0).rgb;
    vec3 up = mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
    vec3 v = pc.base_weight * texelFetch(base, p, 0).rgb + pc.coarse_weight * up;
    imageStore(dst, p, vec4(v, 1.0));
}

#version 450
// Joint bilateral upsampling (Kopf et al. 2007) of the blurred half-resolution SAO term to
// the frame, guided by the full-resolution view depth (level 0 of the sao_depth pyramid), so
// that the AO of a far surface does not bleed onto a near one across a silhouette (and back).
// Half-resolution texel q is the AO of pixel 2q; pixel p lies at p/2 in texel units between
// the texels ⌊p/2⌋ and ⌊p/2⌋ + 1 (weights 1 − f, f with f = 0 or 1/2 per axis), and each of
// the four is weighted further by exp(−Δz²/(2σ²)), Δz the difference of its pixel's view depth
// from p's, σ = depth_sigma_rel · z_p. Where every weight vanishes (p's surface has no texel
// of its own among the four: a sliver narrower than two pixels) the texel nearest in depth is
// taken. An even pixel coincides with its texel (weight 1 on it alone): its value is exact.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D pyramid;   // sao_depth: w = view depth, 0: sky
layout(set = 0, binding = 1) uniform sampler2D half_ao;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D dst;

layout(push_constant) uniform Push {
    float depth_sigma_rel;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    float z = texelFetch(pyramid, p, 0).w;
    ivec2 i0 = p >> 1;
    vec2 f = vec2(p & 1) * 0.5;
    if (z <= 0.0) {
        imageStore(dst, p, vec4(texelFetch(half_ao, i0, 0).r));
        return;
    }
    ivec2 hsize = textureSize(half_ao, 0);
    float sigma = max(pc.depth_sigma_rel * z, 1e-6);
    float sum = 0.0, w_sum = 0.0;
    float nearest = 1.0, best = 1e30;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        float wb = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        if (wb <= 0.0) continue;
        ivec2 q = min(i0 + o, hsize - 1);
        float zq = texelFetch(pyramid, min(2 * q, size - 1), 0).w;
        if (zq <= 0.0) continue;
        float a = texelFetch(half_ao, q, 0).r;
        float dz = zq - z;
        float w = wb * exp(-dz * dz / (2.0 * sigma * sigma));
        sum += w * a;
        w_sum += w;
        if (abs(dz) < best) {
            best = abs(dz);
            nearest = a;
        }
    }
    imageStore(dst, p, vec4(w_sum > 1e-20 ? sum / w_sum : nearest));
}

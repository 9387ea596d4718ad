// What the screen-space GI passes share (ssgi_input, ssgi_mip, ssgi_gather, ssgi_upsample,
// ssgi_reflect; Oetke 2017 §2.3, §5.1–5.4). The geometry pyramid holds per texel the world
// position with the view depth z (meters along the camera axis; 0 marks sky) and the world
// normal.
#ifndef SSGI_GLSL
#define SSGI_GLSL

#define SSGI_PI 3.14159265358979323846

// The camera's unit view direction, from the clip-space z axis.
vec3 ssgi_camera_forward(mat4 inv_view_proj) {
    vec4 a = inv_view_proj * vec4(0.0, 0.0, 0.0, 1.0);
    vec4 b = inv_view_proj * vec4(0.0, 0.0, 1.0, 1.0);
    return normalize(b.xyz / b.w - a.xyz / a.w);
}

// A hash of a texel and a seed to [0, 1) (Jenkins-style integer mixing).
float ssgi_hash(uvec2 p, uint seed) {
    uint h = p.x * 1973u + p.y * 9277u + seed * 26699u;
    h = (h ^ (h >> 16)) * 0x7feb352du;
    h = (h ^ (h >> 15)) * 0x846ca68bu;
    h ^= h >> 16;
    return float(h >> 8) * (1.0 / 16777216.0);
}

// Where world point p was in the previous frame: its texel of `history` (whose w holds each
// texel's clip w then) and the depth agreement weight (1 within 1%, 0 beyond 5%); false
// outside the previous frame. `prev_view_proj`: the previous camera.
bool ssgi_reproject(mat4 prev_view_proj, sampler2D history, vec3 p, out ivec2 texel,
                    out float weight) {
    texel = ivec2(0);
    weight = 0.0;
    vec4 clip = prev_view_proj * vec4(p, 1.0);
    if (clip.w <= 1e-6) return false;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) return false;
    ivec2 size = textureSize(history, 0);
    texel = ivec2(uv * vec2(size));
    float rel = abs(texelFetch(history, texel, 0).w - clip.w) / clip.w;
    weight = 1.0 - smoothstep(0.01, 0.05, rel);
    return true;
}

// Joint bilateral upsampling (Kopf et al. 2007, as modified by Oetke 2017 Eq. 3.3): the value
// at a fine texel from the 2x2 coarse texels around it, each weighted by its bilinear weight,
// its normal's agreement with the fine normal n and its view depth's with the fine depth z,
// compared against the coarse geometry the coarse values were computed at. Where no coarse
// texel agrees (sum of weights below 1e-4) the plain bilinear weights of the non-sky texels
// are used instead, so an edge texel is never left black.
// `fine_px`: the fine texel; `scale`: fine texels per coarse texel (a power of two).
vec3 ssgi_joint_bilateral(sampler2D coarse_value, sampler2D coarse_pos, sampler2D coarse_nrm,
                          ivec2 fine_px, float scale, vec3 n, float z) {
    ivec2 size = textureSize(coarse_value, 0);
    vec2 c = (vec2(fine_px) + 0.5) / scale - 0.5;
    ivec2 i0 = ivec2(floor(c));
    vec2 f = c - vec2(i0);
    vec3 sum = vec3(0.0), sum_plain = vec3(0.0);
    float w_sum = 0.0, w_plain = 0.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 q = clamp(i0 + o, ivec2(0), size - 1);
        float zc = texelFetch(coarse_pos, q, 0).w;
        if (zc <= 0.0) continue;
        float wb = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        vec3 nc = texelFetch(coarse_nrm, q, 0).xyz;
        float wn = pow(max(dot(n, nc), 0.0), 8.0);
        float dz = (zc - z) / (0.05 * z + 1e-3);
        float wz = exp(-dz * dz);
        vec3 v = texelFetch(coarse_value, q, 0).rgb;
        sum += v * wb * wn * wz;
        w_sum += wb * wn * wz;
        sum_plain += v * wb;
        w_plain += wb;
    }
    if (w_sum >= 1e-4) return sum / w_sum;
    return w_plain > 0.0 ? sum_plain / w_plain : vec3(0.0);
}

#endif

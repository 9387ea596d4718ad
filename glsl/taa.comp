#version 450
// Temporal anti-aliasing (Oetke 2017 §4.5, after Karis 2014): the frame was rendered with a
// sub-pixel Halton(2,3) jitter of the projection; the history (the previous output) is
// reprojected with this pixel's depth and the previous frame's camera, clipped in YCoCg
// towards the 3×3 neighbourhood's AABB of the current frame, and blended:
// out = mix(history, current, current_weight). Runs on linear HDR radiance before tone mapping.
// MOTION (scenes with moving objects): a surface pixel's previous position is its motion
// vector from the G-buffer (the point's previous un-jittered NDC minus its current one, from
// the previous model matrix and camera) instead of the camera-only reprojection of its depth;
// the sky keeps the camera's.
// UPSAMPLE (the viewer's TAA upsampling, `post::taa`): `dst` and `history` are larger than
// `current`; see upsample() below.
layout(constant_id = 0) const bool MOTION = false;
layout(constant_id = 1) const bool UPSAMPLE = false;
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D current;
layout(set = 0, binding = 1) uniform sampler2D gb_depth;
layout(set = 0, binding = 2) uniform sampler2D history;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D dst;
layout(set = 0, binding = 4) uniform sampler2D gb_motion;  // MOTION; the depth otherwise

layout(push_constant) uniform Push {
    // Previous un-jittered view-projection times the inverse of this frame's un-jittered one:
    // maps this frame's un-jittered NDC (with depth) to the previous frame's clip space.
    mat4 reproject;
    // This frame's jitter in NDC units (added to clip x/y per w).
    vec2 jitter_ndc;
    // Weight of the current frame (1 − history weight, or 1/(n+1) while n < 1/(1 − weight)
    // frames are in the history, so a static view starts as their plain mean).
    float current_weight;
    // 0: no history yet (first frame): the output is the current frame.
    uint has_history;
} pc;

vec3 rgb_to_ycocg(vec3 c) {
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b, -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}

vec3 ycocg_to_rgb(vec3 c) {
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

// Bilinear history at continuous pixel position `p` (texel centres at +0.5), clamped to the
// edge; by hand, so the rgba32f history needs no linear-filter support.
vec3 history_bilinear(vec2 p, ivec2 size) {
    vec2 f = p - 0.5;
    ivec2 i0 = ivec2(floor(f));
    vec2 t = f - vec2(i0);
    ivec2 hi = size - 1;
    vec3 a = texelFetch(history, clamp(i0, ivec2(0), hi), 0).rgb;
    vec3 b = texelFetch(history, clamp(i0 + ivec2(1, 0), ivec2(0), hi), 0).rgb;
    vec3 c = texelFetch(history, clamp(i0 + ivec2(0, 1), ivec2(0), hi), 0).rgb;
    vec3 d = texelFetch(history, clamp(i0 + ivec2(1, 1), ivec2(0), hi), 0).rgb;
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}

// Clips `h` towards the box centre onto the AABB [lo, hi] (Karis 2014): keeps the history's
// colour where it is plausible, moves it the least distance along the line to the mean.
vec3 clip_to_aabb(vec3 h, vec3 lo, vec3 hi) {
    vec3 centre = 0.5 * (lo + hi);
    vec3 extent = 0.5 * (hi - lo) + 1e-7;
    vec3 v = h - centre;
    vec3 a = abs(v / extent);
    float m = max(a.x, max(a.y, a.z));
    return m > 1.0 ? centre + v / m : h;
}

// Bilinear history with its alpha (the accumulated sample weight under UPSAMPLE).
vec4 history_bilinear4(vec2 p, ivec2 size) {
    vec2 f = p - 0.5;
    ivec2 i0 = ivec2(floor(f));
    vec2 t = f - vec2(i0);
    ivec2 hi = size - 1;
    vec4 a = texelFetch(history, clamp(i0, ivec2(0), hi), 0);
    vec4 b = texelFetch(history, clamp(i0 + ivec2(1, 0), ivec2(0), hi), 0);
    vec4 c = texelFetch(history, clamp(i0 + ivec2(0, 1), ivec2(0), hi), 0);
    vec4 d = texelFetch(history, clamp(i0 + ivec2(1, 1), ivec2(0), hi), 0);
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}

// Upsampling: output pixel `p` of a `size` history from the `in_size` jittered frame.
// The output grid is not jittered: the pixel's centre is its un-jittered position. Frame pixel
// i holds the sample at i + 0.5 − jitter (frame pixels; the projection moved the scene by
// +jitter), so each of the 3×3 frame pixels around the centre weighs exp(−2.29 d²) (Karis
// 2014's fit of Blackman-Harris, as Unreal's TAAU) with d its sample's distance to the centre
// in output pixels: a sample within half a pixel counts fully, one a pixel away a tenth.
// (In units of half the upsampling factor, 2 pixels at 1/4, edges smeared over 3 pixels.)
// The history keeps the weighted mean of the samples it took and their total weight W in
// alpha (as FSR 2 accumulates): out = (W_h · history + Σ w c) / (W_h + Σ w), W capped at
// 1 / current_weight, so it becomes TAA's exponential mean once full. A pixel this frame has
// no sample near gains little and keeps its history; a still camera fills every output pixel
// over the 16 jitters with the samples that fell near it.
void upsample(ivec2 p, ivec2 size) {
    ivec2 in_size = textureSize(current, 0);
    vec2 ratio = vec2(in_size) / vec2(size);
    vec2 jitter_px = pc.jitter_ndc * 0.5 * vec2(in_size);
    vec2 centre = (vec2(p) + 0.5) * ratio;  // in frame pixels
    vec2 unit = ratio;  // one output pixel, in frame pixels
    ivec2 c = ivec2(floor(centre));
    vec3 lo = vec3(1e30), hi = vec3(-1e30);
    vec3 sum = vec3(0.0), nearest = vec3(0.0);
    float weight = 0.0, nearest_d2 = 1e30;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = clamp(c + ivec2(dx, dy), ivec2(0), in_size - 1);
            vec3 col = max(texelFetch(current, q, 0).rgb, vec3(0.0));
            vec2 d = (vec2(q) + 0.5 - jitter_px - centre) / unit;
            float w = exp(-2.29 * dot(d, d));
            if (dot(d, d) < nearest_d2) {
                nearest_d2 = dot(d, d);
                nearest = col;
            }
            sum += w * col;
            weight += w;
            vec3 y = rgb_to_ycocg(col);
            lo = min(lo, y);
            hi = max(hi, y);
        }
    }
    // The 3×3 holds the sample nearest the centre (samples lie on the frame's pixel grid,
    // shifted by the jitter: within √2/2 frame pixels), but at 1/8 that is 5.7 output pixels,
    // whose weight exp(−2.29 · 32) ≈ 1e-32 is near float's least: where the weights vanish the
    // fresh colour is the nearest sample's (a nearest-neighbour upscale, that its history
    // replaces as nearer samples come).
    float w_max = 1.0 / pc.current_weight;
    vec3 mean = weight > 1e-30 ? sum / weight : nearest;
    vec4 fresh = vec4(mean, min(weight, w_max));
    if (pc.has_history == 0u) {
        imageStore(dst, p, fresh);
        return;
    }
    vec2 ndc = (vec2(p) + 0.5) / vec2(size) * 2.0 - 1.0;
    ivec2 at = clamp(c, ivec2(0), in_size - 1);
    float depth = texelFetch(gb_depth, at, 0).r;
    vec4 prev = pc.reproject * vec4(ndc, depth, 1.0);
    vec2 prev_ndc = prev.xy / prev.w;
    bool in_front = prev.w > 0.0;
    if (MOTION && depth < 1.0) {
        prev_ndc = ndc + texelFetch(gb_motion, at, 0).xy;
        in_front = true;
    }
    vec2 prev_px = (prev_ndc * 0.5 + 0.5) * vec2(size);
    bool inside = in_front && all(greaterThanEqual(prev_px, vec2(0.0))) && all(lessThanEqual(prev_px, vec2(size)));
    if (!inside) {
        imageStore(dst, p, fresh);
        return;
    }
    vec4 hist = history_bilinear4(prev_px, size);
    vec3 h = ycocg_to_rgb(clip_to_aabb(rgb_to_ycocg(max(hist.rgb, vec3(0.0))), lo, hi));
    float w_h = clamp(hist.a, 0.0, w_max);
    float total = w_h + weight;
    // No weight either side (far from every sample so far, at 1/8): the clipped history.
    vec3 colour = total > 1e-30 ? (max(h, vec3(0.0)) * w_h + sum) / total : max(h, vec3(0.0));
    imageStore(dst, p, vec4(colour, min(total, w_max)));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    if (UPSAMPLE) {
        upsample(p, size);
        return;
    }
    vec3 cur = max(texelFetch(current, p, 0).rgb, vec3(0.0));
    if (pc.has_history == 0u) {
        imageStore(dst, p, vec4(cur, 1.0));
        return;
    }
    vec3 lo = vec3(1e30), hi = vec3(-1e30);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = clamp(p + ivec2(dx, dy), ivec2(0), size - 1);
            vec3 y = rgb_to_ycocg(max(texelFetch(current, q, 0).rgb, vec3(0.0)));
            lo = min(lo, y);
            hi = max(hi, y);
        }
    }
    // The pixel centre's NDC was rasterized with the jittered projection: without the jitter
    // it is ndc − jitter. Its previous position plus this frame's jitter is where the history
    // holds the same point under this pixel (a static camera reads the pixel centre itself).
    vec2 ndc = (vec2(p) + 0.5) / vec2(size) * 2.0 - 1.0;
    float depth = texelFetch(gb_depth, p, 0).r;
    vec4 prev = pc.reproject * vec4(ndc - pc.jitter_ndc, depth, 1.0);
    vec2 prev_ndc = prev.xy / prev.w + pc.jitter_ndc;
    bool in_front = prev.w > 0.0;
    if (MOTION && depth < 1.0) {
        // (ndc − jitter) + motion is the previous un-jittered position; the jitter added back.
        prev_ndc = ndc + texelFetch(gb_motion, p, 0).xy;
        in_front = true;
    }
    vec2 prev_px = (prev_ndc * 0.5 + 0.5) * vec2(size);
    bool inside = in_front && all(greaterThanEqual(prev_px, vec2(0.0))) && all(lessThanEqual(prev_px, vec2(size)));
    if (!inside) {
        imageStore(dst, p, vec4(cur, 1.0));
        return;
    }
    vec3 h = rgb_to_ycocg(max(history_bilinear(prev_px, size), vec3(0.0)));
    h = ycocg_to_rgb(clip_to_aabb(h, lo, hi));
    imageStore(dst, p, vec4(mix(max(h, vec3(0.0)), cur, pc.current_weight), 1.0));
}

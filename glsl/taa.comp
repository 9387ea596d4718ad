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
layout(constant_id = 0) const bool MOTION = false;
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

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
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

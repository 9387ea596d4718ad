#version 450
// Temporal accumulation of the indirect light (after Schied et al. 2017, "Spatiotemporal
// Variance-Guided Filtering", §4.1): the previous frames' accumulated indirect light is
// reprojected to this frame's pixels and blended with this frame's estimate,
//   c = mix(c_history, c_now, 1 / n),  n = min(n_history + 1, N),
// so a still pixel holds the plain mean of its n frames (the sample pattern advances every
// frame: N frames of K rays are N·K rays), and after N frames an exponential mean.
//
// Reprojection: the pixel's surface point p (this frame's depth) seen from the previous frame's
// camera (push constants: its un-jittered view-projection relative to its own position, and
// the camera's move since then), or, with MOTION (scenes with moving objects), the G-buffer's
// motion vector at surface pixels. The history is read bilinearly; each of the four taps
// counts only where the surface it stored is this one (disocclusion, Schied et al. §4.1): the
// tap's point (its pixel's ray from the previous camera, at its stored distance) lies within
// PLANE_TOLERANCE of p's tangent plane (relative to the distance, so that slanted surfaces
// and coarse pixels keep their neighbours, unlike a test of the distance alone), and its
// normal within NORMAL_COS of this one. No valid tap: the pixel starts over (n = 1).
//
// Moments (§4.2): the history also keeps the mean of the squared luminance; with the mean
// luminance (that of c, exactly, since luminance is linear) it gives the variance of one
// frame's estimate, which gi_filter divides by n for the variance of the mean: the spatial
// filter steps back as samples accumulate.
//
// Outputs: rgb the accumulated light, a the history length n; aux x the mean squared
// luminance, y the camera distance of the pixel's surface, zw its octahedral normal.
#include "frame.glsl"

layout(constant_id = 0) const bool MOTION = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_normal;
layout(set = 0, binding = 2) uniform sampler2D gb_depth;
layout(set = 0, binding = 3) uniform sampler2D current;
layout(set = 0, binding = 4) uniform sampler2D history;
layout(set = 0, binding = 5) uniform sampler2D history_aux;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D out_color;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D out_aux;
layout(set = 0, binding = 8) uniform sampler2D gb_motion;  // MOTION; the depth otherwise

layout(push_constant) uniform Push {
    // The previous frame's un-jittered view-projection with its camera at the origin.
    mat4 prev_view_proj;
    // xyz: this frame's camera position minus the previous one; w: 1 under orthographic
    // projection.
    vec4 camera_move;
    // xyz: the previous frame's viewing direction.
    vec4 prev_forward;
    // The longest history, N.
    uint max_frames;
    // 0: no history (the first frame, a resize, a light change): every pixel starts over.
    uint has_history;
} pc;

// A point this close to p's tangent plane, relative to its distance, is on p's surface: as
// gi_filter's plane test (0.02), with room for a moving object's change between frames.
const float PLANE_TOLERANCE = 0.03;
// About 25°: a normal that turned more is another surface (or another side of one).
const float NORMAL_COS = 0.9;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.xy;
    if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return e;
}

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

// The distance by which a camera orders the points on one pixel's ray (frame.glsl's
// camera_distance), for a point `q` relative to the camera.
float distance_from(vec3 q, vec3 forward, bool ortho) {
    return ortho ? dot(q, forward) : length(q);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.zw);
    if (any(greaterThanEqual(px, size))) return;
    vec3 now = max(texelFetch(current, px, 0).rgb, vec3(0.0));
    float depth = texelFetch(gb_depth, px, 0).r;
    if (depth >= 1.0) {
        imageStore(out_color, px, vec4(now, 0.0));
        imageStore(out_aux, px, vec4(0.0, -1.0, 0.0, 0.0));
        return;
    }
    bool ortho = pc.camera_move.w > 0.5;
    vec3 n = normalize(texelFetch(gb_normal, px, 0).xyz);
    // p relative to this frame's camera, then to the previous one.
    vec3 p = pixel_world_position(frame.inv_view_proj, vec3(0.0), px, vec2(size), depth);
    vec3 q = p + pc.camera_move.xyz;
    float d_now = distance_from(p, frame.camera_forward.xyz, ortho);
    float d_expected = distance_from(q, pc.prev_forward.xyz, ortho);
    vec4 clip = pc.prev_view_proj * vec4(q, 1.0);
    vec2 prev_ndc = clip.xy / clip.w;
    bool in_front = clip.w > 0.0;
    if (MOTION) {
        // The motion vector: the point's previous un-jittered NDC minus its current one.
        vec2 ndc = (vec2(px) + 0.5) / vec2(size) * 2.0 - 1.0;
        prev_ndc = ndc - frame.jitter_ndc.xy + texelFetch(gb_motion, px, 0).xy;
        in_front = true;
    }
    vec3 history_sum = vec3(0.0);
    float m2_sum = 0.0, n_sum = 0.0, w_sum = 0.0;
    if (pc.has_history != 0u && in_front) {
        // The previous camera's unprojection (relative to it), for the taps' points.
        mat4 prev_inverse = inverse(pc.prev_view_proj);
        vec2 f = (prev_ndc * 0.5 + 0.5) * vec2(size) - 0.5;
        ivec2 i0 = ivec2(floor(f));
        vec2 t = f - vec2(i0);
        for (int k = 0; k < 4; ++k) {
            ivec2 o = ivec2(k & 1, k >> 1);
            ivec2 tap = i0 + o;
            if (any(lessThan(tap, ivec2(0))) || any(greaterThanEqual(tap, size))) continue;
            vec4 aux = texelFetch(history_aux, tap, 0);
            if (aux.y < 0.0) continue;  // sky, or never written
            vec2 tap_ndc = (vec2(tap) + 0.5) / vec2(size) * 2.0 - 1.0;
            vec4 a = prev_inverse * vec4(tap_ndc, 0.0, 1.0);
            vec4 b = prev_inverse * vec4(tap_ndc, 1.0, 1.0);
            vec3 near = a.xyz / a.w;
            vec3 dir = normalize(b.xyz / b.w - near);
            // Perspective: the stored distance is from the camera (the origin) along the ray;
            // orthographic: the depth along the viewing direction.
            vec3 tap_point = ortho ? near + dir * (aux.y - dot(near, pc.prev_forward.xyz)) : dir * aux.y;
            if (abs(dot(n, tap_point - q)) > PLANE_TOLERANCE * d_expected) continue;
            if (dot(oct_decode(aux.zw), n) < NORMAL_COS) continue;
            float w = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
            vec4 h = texelFetch(history, tap, 0);
            history_sum += w * h.rgb;
            m2_sum += w * aux.x;
            n_sum += w * h.a;
            w_sum += w;
        }
    }
    float lum = luminance(now);
    vec3 color = now;
    float m2 = lum * lum;
    float frames = 1.0;
    // Taps of less than 1% weight in all are too few to carry a history.
    if (w_sum > 0.01) {
        float n_prev = n_sum / w_sum;
        frames = min(floor(n_prev + 0.5) + 1.0, float(max(pc.max_frames, 1u)));
        float a = 1.0 / frames;
        color = mix(history_sum / w_sum, now, a);
        m2 = mix(m2_sum / w_sum, m2, a);
    }
    imageStore(out_color, px, vec4(color, frames));
    imageStore(out_aux, px, vec4(m2, d_now, oct_encode(n)));
}

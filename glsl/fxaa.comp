#version 450
// FXAA 3.11, quality variant (Lottes 2011), on the tone-mapped, sRGB-encoded image. A pixel
// whose 4-neighbourhood luma contrast is below max(1/12, 1/6 · local maximum) is left
// unchanged. Otherwise: the edge is horizontal or vertical by the 3×3 second differences; the
// pixel's side of the edge is the neighbour with the larger gradient; the edge is followed
// both ways on the half-texel line between the two rows (columns) until its luma leaves the
// pair's average by a quarter of the gradient; the nearer end gives the offset
// 0.5 − distance / span length across the edge (only if the luma there changes sign as at
// this pixel), at least the sub-pixel term; one bilinear fetch at the offset position.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D ldr_in;   // bilinear, clamp to edge
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D ldr_out;

const float EDGE_THRESHOLD = 0.166;
const float EDGE_THRESHOLD_MIN = 0.0833;
const float SUBPIX = 0.75;
const int STEPS = 8;
const float STEP_SIZES[STEPS] = float[STEPS](1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);

// Luma of encoded (perceptual) values, Rec. 709 weights.
float luma(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

float luma_at(ivec2 p, ivec2 hi) { return luma(texelFetch(ldr_in, clamp(p, ivec2(0), hi), 0).rgb); }

float luma_uv(vec2 uv) { return luma(textureLod(ldr_in, uv, 0.0).rgb); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(ldr_out);
    if (any(greaterThanEqual(p, size))) return;
    ivec2 hi = size - 1;
    vec2 rcp_frame = 1.0 / vec2(size);
    vec4 m = texelFetch(ldr_in, p, 0);
    float lm = luma(m.rgb);
    float ln = luma_at(p + ivec2(0, -1), hi);
    float ls = luma_at(p + ivec2(0, 1), hi);
    float lw = luma_at(p + ivec2(-1, 0), hi);
    float le = luma_at(p + ivec2(1, 0), hi);
    float lmin = min(lm, min(min(ln, ls), min(lw, le)));
    float lmax = max(lm, max(max(ln, ls), max(lw, le)));
    float range = lmax - lmin;
    if (range < max(EDGE_THRESHOLD_MIN, lmax * EDGE_THRESHOLD)) {
        imageStore(ldr_out, p, m);
        return;
    }
    float lnw = luma_at(p + ivec2(-1, -1), hi);
    float lne = luma_at(p + ivec2(1, -1), hi);
    float lsw = luma_at(p + ivec2(-1, 1), hi);
    float lse = luma_at(p + ivec2(1, 1), hi);

    // Horizontal or vertical edge: weighted second differences across rows vs columns.
    float edge_horz = abs(lnw - 2.0 * lw + lsw) + 2.0 * abs(ln - 2.0 * lm + ls) + abs(lne - 2.0 * le + lse);
    float edge_vert = abs(lnw - 2.0 * ln + lne) + 2.0 * abs(lw - 2.0 * lm + le) + abs(lsw - 2.0 * ls + lse);
    bool horz_span = edge_horz >= edge_vert;
    // Sub-pixel aliasing: how far the pixel stands out of its 3×3 low-pass.
    float subpix_a = 2.0 * (ln + ls + lw + le) + (lnw + lne + lsw + lse);
    float subpix_c = clamp(abs(subpix_a / 12.0 - lm) / range, 0.0, 1.0);
    float subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    float subpix_h = subpix_f * subpix_f * SUBPIX;

    float l_neg = horz_span ? ln : lw;   // the neighbours across the edge
    float l_pos = horz_span ? ls : le;
    float gradient_neg = abs(l_neg - lm);
    float gradient_pos = abs(l_pos - lm);
    bool pair_neg = gradient_neg >= gradient_pos;
    float gradient = max(gradient_neg, gradient_pos);
    float length_sign = (horz_span ? rcp_frame.y : rcp_frame.x) * (pair_neg ? -1.0 : 1.0);
    float l_pair = (pair_neg ? l_neg : l_pos) + lm;   // twice the edge's middle luma

    // Walk along the edge on the line half a texel towards the chosen neighbour.
    vec2 pos_m = (vec2(p) + 0.5) * rcp_frame;
    vec2 pos_b = pos_m;
    if (horz_span) pos_b.y += 0.5 * length_sign; else pos_b.x += 0.5 * length_sign;
    vec2 off = horz_span ? vec2(rcp_frame.x, 0.0) : vec2(0.0, rcp_frame.y);
    vec2 pos_n = pos_b - off;
    vec2 pos_p = pos_b + off;
    float gradient_scaled = gradient * 0.25;
    float end_n = luma_uv(pos_n) - 0.5 * l_pair;
    float end_p = luma_uv(pos_p) - 0.5 * l_pair;
    bool done_n = abs(end_n) >= gradient_scaled;
    bool done_p = abs(end_p) >= gradient_scaled;
    for (int i = 1; i < STEPS && !(done_n && done_p); ++i) {
        if (!done_n) {
            pos_n -= off * STEP_SIZES[i];
            end_n = luma_uv(pos_n) - 0.5 * l_pair;
            done_n = abs(end_n) >= gradient_scaled;
        }
        if (!done_p) {
            pos_p += off * STEP_SIZES[i];
            end_p = luma_uv(pos_p) - 0.5 * l_pair;
            done_p = abs(end_p) >= gradient_scaled;
        }
    }
    float dst_n = horz_span ? pos_m.x - pos_n.x : pos_m.y - pos_n.y;
    float dst_p = horz_span ? pos_p.x - pos_m.x : pos_p.y - pos_m.y;
    bool m_below = lm - 0.5 * l_pair < 0.0;
    bool good_n = (end_n < 0.0) != m_below;
    bool good_p = (end_p < 0.0) != m_below;
    bool nearer_n = dst_n < dst_p;
    float pixel_offset = 0.5 - min(dst_n, dst_p) / (dst_n + dst_p);
    float offset = max((nearer_n ? good_n : good_p) ? pixel_offset : 0.0, subpix_h);
    vec2 pos = pos_m;
    if (horz_span) pos.y += offset * length_sign; else pos.x += offset * length_sign;
    imageStore(ldr_out, p, vec4(textureLod(ldr_in, pos, 0.0).rgb, m.a));
}

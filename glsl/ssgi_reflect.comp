#version 450
// Screen-space reflection rays (Oetke 2017 §5.4): per Phong or GGX pixel one ray, marched
// hierarchically on the Hi-Z pyramid of inverse view depth (ssgi_reflect_hiz) to the first
// texel whose surface the ray reaches within a thickness. Its direction (LOBE, `--ssr-rays`):
// - mirror (the thesis's): r = reflect(−v, n), deterministic; the lobe's width enters through
//   the cone footprint at the hit (below);
// - lobe: a direction importance-sampled from the pixel's lobe, a new one every frame (an R2
//   sequence in the frame index, Cranley-Patterson rotated per pixel), read at the colour's
//   finest level; the history averages the samples. GGX: reflection about a visible normal
//   (Heitz 2018), whose f·cos/pdf is F(v·h)·G1(l); Phong: cosⁿ about the mirror direction, f·cos/pdf
//   = ρs (n+2)/(n+1) (n·l). The split sum (Eq. 2.15–2.19) multiplies L_spec by the lobe's
//   directional albedo afterwards (ssgi_upsample), so a sample carries its weight divided by
//   the weight's mean, w = G1(l)/(A + B) (A + B = E[G1(l)] is the split-sum table with F0 = 1),
//   or (n+2)/(n+1)·(n·l)/(n·v) for Phong (its mean n·v, see ssgi_upsample), and E[w·L] is the
//   lobe-weighted mean radiance the split sum asks for. Lobes whose half-maximum angle is
//   below half a pixel's keep the mirror ray (then both choices give the same image).
// The ray is marched in screen space, where its pixel position and its
// inverse clip w are both linear in the parameter t of the projected segment:
// - at level L the ray's segment inside its current cell is compared with the cell's nearest
//   surface: entirely in front of it, the march skips to the cell's exit and goes up a level;
//   otherwise it descends; at level 0 a segment reaching behind the surface hits it when its
//   nearest point lies within `thickness` (relative to the surface's depth) behind it, else
//   the ray passes behind and goes on at level 0.
// At a mirror ray's hit the lit colour is read from the colour pyramid at the level whose texel
// matches the lobe's cone footprint there: diameter 2·d·tan θ at hit distance d, θ the lobe's
// half-maximum angle (Phong cos^n: cos θ = 2^(−1/n); GGX through its Phong equivalent
// n = 2/α² − 2, Walter et al. 2007), over the pixel's width at the hit's depth.
// The ray's confidence a fades at the screen's edge, near the maximum distance, for rays
// toward the camera and at back faces; misses have a = 0. Output premultiplied, (a·L, a) (lobe
// samples: (w·a·L, w·a)), so the blur and the history blend linearly; ssgi_upsample completes
// a·L + (1 − a)·fallback. The result is blended with this pixel's reprojected history (τ·w as
// ssgi_upsample; lobe samples: while fewer than 1/(1 − τ) frames were traced, τ = n/(n+1), the
// plain mean of the n + 1 samples), the history's depth agreement read from the GI history's
// clip w.
#include "frame.glsl"
#include "ssgi.glsl"
#include "brdf.glsl"
#define GI_OWN_PUSH
#include "gi_common.glsl"
#include "material_lobe.glsl"

layout(constant_id = 0) const bool LOBE = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D fine_pos;     // GI level 0: position, z
layout(set = 0, binding = 2) uniform sampler2D gb_normal;    // w: Phong n or GGX roughness
layout(set = 0, binding = 3) uniform sampler2D gb_specular;  // rgb ρs or F0, a lobe kind
layout(set = 0, binding = 4) uniform sampler2D hiz;          // all levels: nearest 1/z
layout(set = 0, binding = 5) uniform sampler2D lit_color;    // all levels, linear sampler
layout(set = 0, binding = 6) uniform sampler2D ssr_history;  // premultiplied (a·L, a)
layout(set = 0, binding = 7) uniform sampler2D gi_history;   // w: clip w last frame
layout(set = 0, binding = 8, std430) readonly buffer PrevCamera { mat4 prev_view_proj; };
layout(set = 0, binding = 9, rgba32f) uniform writeonly image2D traced;
layout(set = 0, binding = 10) uniform sampler2D brdf_lut;    // A, B (LOBE in GGX scenes)

layout(push_constant) uniform Push {
    float max_distance_m;   // ray length in world space
    float thickness;        // hit shell behind a surface, relative to its depth
    float pixel_angle;      // 2 tan(fov_y/2) / height: a pixel's width per meter of depth
    float history_weight;   // τ
    int levels;             // of the Hi-Z and colour pyramids
    int max_steps;
    uint frame;             // frames traced before this one (the lobe samples' index)
} pc;

// The R2 sequence's steps (Roberts 2018): the fractional parts of k/φ₂ and k/φ₂², φ₂ the
// plastic number, a low-discrepancy sequence in the frame index.
const vec2 R2 = vec2(0.7548776662466927, 0.5698402909980532);

// Fades: 1 inside, smoothly to 0 over the outer 5% of the screen.
const float EDGE_FADE = 0.05;

// The lobe's half-maximum angle's tangent: Phong cos^n falls to half at cos θ = 2^(−1/n).
float lobe_tan(float kind, float w) {
    float n = w;
    if (kind > 1.5) {
        float alpha = max(w * w, 1e-3);
        n = 2.0 / (alpha * alpha) - 2.0;
    }
    float c = exp2(-1.0 / max(n, 1e-3));
    return sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-4);
}

// Marches the screen-space segment from s0 (inverse clip w k0) to s1 (k1), t in [0, 1];
// returns the hit texel, or ivec2(−1) for a miss.
ivec2 march(vec2 s0, vec2 s1, float k0, float k1) {
    vec2 d = s1 - s0;
    vec2 size = vec2(textureSize(hiz, 0));
    // The segment's end inside the screen (a ray leaving it is a miss past there).
    float t_end = 1.0;
    for (int i = 0; i < 2; ++i) {
        if (d[i] > 0.0) t_end = min(t_end, (size[i] - s0[i]) / d[i]);
        if (d[i] < 0.0) t_end = min(t_end, -s0[i] / d[i]);
    }
    vec2 inv_d = vec2(abs(d.x) > 1e-6 ? 1.0 / d.x : 1e12, abs(d.y) > 1e-6 ? 1.0 / d.y : 1e12);
    vec2 dir_step = step(vec2(0.0), d);
    // A nudge past a cell's boundary, 1/100 pixel along the ray.
    float nudge = 0.01 / max(length(d), 1e-6);
    // Start where the ray leaves its own pixel.
    vec2 t_cells = ((floor(s0) + dir_step) - s0) * inv_d;
    float t = max(min(t_cells.x, t_cells.y), 0.0) + nudge;
    int level = 0;
    for (int i = 0; i < pc.max_steps && t < t_end; ++i) {
        vec2 s = s0 + d * t;
        float cell = exp2(float(level));
        // Level sizes as Vulkan's mips: halved, rounded down (textureSize with a varying lod
        // is not relied on; lavapipe answered wrongly).
        ivec2 level_size = max(textureSize(hiz, 0) >> level, ivec2(1));
        ivec2 c = clamp(ivec2(floor(s / cell)), ivec2(0), level_size - 1);
        vec2 exits = ((vec2(c) + dir_step) * cell - s0) * inv_d;
        float t_exit = min(min(exits.x, exits.y), t_end);
        float k_in = mix(k0, k1, t), k_out = mix(k0, k1, t_exit);
        float surface = texelFetch(hiz, c, level).r;
        if (min(k_in, k_out) > surface) {
            // The whole segment is in front of the cell's nearest surface.
            t = t_exit + nudge;
            level = min(level + 1, pc.levels - 1);
        } else if (level > 0) {
            level -= 1;
        } else {
            // Level 0: the segment reaches this texel's surface or behind it.
            float nearest_ray = max(k_in, k_out);
            if (1.0 / nearest_ray <= (1.0 + pc.thickness) / surface) return c;
            t = t_exit + nudge;
        }
    }
    return ivec2(-1);
}

// The traced (a·L, a) of the ray from world point x along r, read at the colour level of a
// cone of half-angle tangent `cone_tan` (0: the finest level).
vec4 trace(vec3 x, vec3 r, float cone_tan) {
    vec3 forward = ssgi_camera_forward(frame.inv_view_proj);
    // Rays toward the camera: full weight while r·forward ≥ 0, none from −0.5 on.
    float toward = 1.0 - smoothstep(0.0, 0.5, -dot(r, forward));
    if (toward <= 0.0) return vec4(0.0);
    vec4 c0 = frame.view_proj * vec4(x, 1.0);
    vec4 c1 = frame.view_proj * vec4(x + r * pc.max_distance_m, 1.0);
    // Keep the segment in front of the camera (clip w above 1% of the start's).
    float w_min = 0.01 * c0.w;
    if (c1.w < w_min) c1 = mix(c0, c1, (c0.w - w_min) / (c0.w - c1.w));
    vec2 size = vec2(textureSize(hiz, 0));
    vec2 s0 = (c0.xy / c0.w * 0.5 + 0.5) * size;
    vec2 s1 = (c1.xy / c1.w * 0.5 + 0.5) * size;
    if (length(s1 - s0) < 1.0) return vec4(0.0);
    ivec2 hit = march(s0, s1, 1.0 / c0.w, 1.0 / c1.w);
    if (hit.x < 0) return vec4(0.0);
    vec4 hit_pos = texelFetch(fine_pos, hit, 0);
    vec3 hit_n = normalize(texelFetch(gb_normal, hit, 0).xyz);
    float dist_m = length(hit_pos.xyz - x);
    vec2 uv = (vec2(hit) + 0.5) / size;
    vec2 border = min(uv, 1.0 - uv);
    float edge = smoothstep(0.0, EDGE_FADE, min(border.x, border.y));
    float far = 1.0 - smoothstep(0.8, 1.0, dist_m / pc.max_distance_m);
    float front = clamp(-4.0 * dot(hit_n, r), 0.0, 1.0);
    float a = toward * edge * far * front;
    float footprint_px = 2.0 * dist_m * cone_tan / (hit_pos.w * pc.pixel_angle);
    float lod = clamp(log2(max(footprint_px, 1.0)), 0.0, float(pc.levels - 1));
    // The half-float pyramid holds pre-exposed colour (ssgi_reflect_hiz.comp).
    vec3 color = textureLod(lit_color, uv, lod).rgb * frame.radiance_scale.y;
    return vec4(a * color, a);
}

// The split-sum table's A + B at (n·v, roughness): E[G1(l)] over the visible normals.
float lut_mean_g1(float n_dot_v, float roughness) {
    ivec2 size = textureSize(brdf_lut, 0);
    ivec2 t = min(ivec2(vec2(n_dot_v, roughness) * vec2(size)), size - 1);
    vec2 ab = texelFetch(brdf_lut, t, 0).rg;
    return ab.x + ab.y;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(traced)))) return;
    vec4 pz = texelFetch(fine_pos, p, 0);
    vec4 lobe = texelFetch(gb_specular, p, 0);
    if (pz.w <= 0.0 || lobe.a < 0.5) {
        imageStore(traced, p, vec4(0.0));
        return;
    }
    vec4 nw = texelFetch(gb_normal, p, 0);
    vec3 n = normalize(nw.xyz);
    vec3 v = normalize(frame.camera_position.xyz - pz.xyz);
    vec3 r = reflect(-v, n);
    float cone_tan = lobe_tan(lobe.a, nw.w);
    // A lobe narrower than the pixel itself: the mirror ray is its sample.
    bool sampled = LOBE && cone_tan > 0.5 * pc.pixel_angle;
    float w = 1.0;
    if (sampled) {
        vec2 u = fract(pixel_rotation(uvec2(p), 0u) + float(pc.frame) * R2);
        float n_dot_v = clamp(dot(n, v), 0.0, 1.0);
        if (lobe.a > 1.5) {
            float roughness = clamp(nw.w, 0.0, 1.0);
            float alpha = max(roughness * roughness, 1e-4);
            r = reflect(-v, ggx_visible_normal(n, v, alpha, u));
            float c = dot(n, r);
            w = c > 0.0 ? ggx_g1(alpha, c) / max(lut_mean_g1(n_dot_v, roughness), 1e-4) : 0.0;
        } else {
            r = phong_direction(r, nw.w, u);
            float c = dot(n, r);
            w = c > 0.0 ? (nw.w + 2.0) / (nw.w + 1.0) * c / max(n_dot_v, 1e-4) : 0.0;
        }
        cone_tan = 0.0;
    }
    vec4 value = w > 0.0 ? w * trace(pz.xyz, r, cone_tan) : vec4(0.0);
    float tau = pc.history_weight;
    if (sampled) tau = min(tau, float(pc.frame) / float(pc.frame + 1u));
    ivec2 texel;
    float weight;
    if (ssgi_reproject(prev_view_proj, gi_history, pz.xyz, texel, weight)) {
        value = mix(value, texelFetch(ssr_history, texel, 0), tau * weight);
    }
    imageStore(traced, p, value);
}

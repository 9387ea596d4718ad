// Importance sampling of the environment map (`gi.env_sampling`): directions drawn by the
// map's luminance times sin(theta), from the tables `scene::environment::EnvironmentCdf` builds
// at load (a marginal CDF over rows, a conditional CDF per row; tools/envis_twin.py is the
// numpy oracle both follow), and the density of any direction under that strategy, for
// multiple importance sampling with the BSDF's samples (Veach 1997, §9.2; Pharr, Jakob and
// Humphreys 2016, §14.2.4 for the piecewise-constant 2D distribution on the sphere).
//
// The density is piecewise constant in (u, v): a texel's probability p_t spread uniformly
// over its (u, v) cell, so per solid angle (dw = 2 pi^2 sin(theta) du dv)
//   p(w) = p_t W H / (2 pi^2 sin(theta)),
// theta at the point itself. env_pdf looks up the texel the direction falls in (nearest, the
// cell the sampler drew it from), not the bilinear footprint of the radiance lookup; the CDF's
// weights are smoothed over that footprint so that every direction with radiance has density.
//
// The includer declares ENV_CDF_BINDING and includes environment.glsl (environment_uv,
// environment_direction, `frame.environment.w` the rotation) before this file.
#ifndef ENVIRONMENT_SAMPLING_GLSL
#define ENVIRONMENT_SAMPLING_GLSL

layout(set = 0, binding = ENV_CDF_BINDING, std430) readonly buffer EnvironmentCdf {
    uvec4 env_cdf_size;  // width, height, the bits of alpha (env_map_share), 0
    float env_cdf[];     // marginal (height + 1), then per row the conditional (width + 1)
};

// alpha in [0, 1/2]: the share of the environment's samples to draw from the map, the rest
// from the BSDF: 1/2 where a majority of the map's power lies in 1% of the sphere (a sun), 0
// otherwise (a smooth sky: the BSDF's samples alone, as without importance sampling);
// EnvironmentCdf::map_share decides it once per map.
float env_map_share() {
    return uintBitsToFloat(env_cdf_size.z);
}

// The interval i in [0, n) with cdf[base + i] <= u < cdf[base + i + 1]: the last i whose start
// is <= u, so empty intervals (a black texel or row) are never returned (cdf[base] = 0 and
// cdf[base + n] = 1 > u).
uint env_find(uint base, uint n, float u) {
    uint lo = 0u, hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        if (env_cdf[base + mid] <= u) lo = mid;
        else hi = mid - 1u;
    }
    return lo;
}

// The density per solid angle of a point at map coordinate v in texel (x, y).
float env_texel_pdf(uint x, uint y, float v) {
    uint w = env_cdf_size.x, h = env_cdf_size.y;
    uint row = h + 1u + y * (w + 1u);
    float p = (env_cdf[y + 1u] - env_cdf[y]) * (env_cdf[row + x + 1u] - env_cdf[row + x]);
    float s = sin(ENVIRONMENT_PI * v);
    return s > 0.0 ? p * float(w * h) / (2.0 * ENVIRONMENT_PI * ENVIRONMENT_PI * s) : 0.0;
}

// A direction drawn from the map's density with u uniform in [0, 1)^2 (u.y the row, u.x the
// column, each rescaled within its interval to place the point in the texel, so stratified u
// stay stratified), and in `pdf` its density per solid angle (0: discard the sample).
vec3 env_sample(vec2 u, out float pdf) {
    uint w = env_cdf_size.x, h = env_cdf_size.y;
    u = min(u, vec2(0.99999994));
    uint y = env_find(0u, h, u.y);
    float m0 = env_cdf[y], m1 = env_cdf[y + 1u];
    uint row = h + 1u + y * (w + 1u);
    uint x = env_find(row, w, u.x);
    float c0 = env_cdf[row + x], c1 = env_cdf[row + x + 1u];
    float fy = clamp((u.y - m0) / max(m1 - m0, 1e-30), 0.0, 1.0);
    float fx = clamp((u.x - c0) / max(c1 - c0, 1e-30), 0.0, 1.0);
    vec2 uv = vec2((float(x) + fx) / float(w), (float(y) + fy) / float(h));
    pdf = env_texel_pdf(x, y, uv.y);
    return environment_direction(uv, frame.environment.w);
}

// The density per solid angle with which env_sample draws unit direction d.
float env_pdf(vec3 d) {
    uint w = env_cdf_size.x, h = env_cdf_size.y;
    vec2 uv = environment_uv(d, frame.environment.w);
    uint x = min(uint(uv.x * float(w)), w - 1u);
    uint y = min(uint(uv.y * float(h)), h - 1u);
    return env_texel_pdf(x, y, uv.y);
}

// The balance heuristic's weight n_a p_a / (n_a p_a + n_b p_b) (Veach 1997, eq. 9.10), as a
// ratio so that the large densities of narrow lobes do not overflow.
float env_balance(float na_pa, float nb_pb) {
    if (nb_pb <= 0.0) return 1.0;
    if (na_pa <= 0.0) return 0.0;
    return 1.0 / (1.0 + nb_pb / na_pa);
}

#endif

// Shared by the GI passes: push constants, sampling, the voxel grid accessors.
#ifndef GI_COMMON_GLSL
#define GI_COMMON_GLSL

#define PI 3.14159265358979323846

// Mirrors `GpuGiPush` in src/gi/gi_common.rs (checked against this block by name, offset and
// size when a pipeline is created). Passes with their own push block (the VPL passes) define
// GI_OWN_PUSH before including this file.
#ifndef GI_OWN_PUSH
layout(push_constant) uniform GiPush {
    mat4 world_to_voxel;
    ivec3 dims;                  // voxels x, y, depth
    int max_level;               // the highest mip level of the hierarchy
    float radius_m;              // ray length
    float normal_offset_voxels;  // self-intersection offset along the normal, k1 (voxel diagonals)
    float hit_tolerance_voxels;  // light-map hit tolerance (voxel diagonals)
    float voxel_diagonal_m;
    uint rays;                   // rays per pixel
    uint start_level;            // mip level the traversal starts at
    uint max_iterations;         // traversal steps before a ray gives up
    uint seed;                   // per-pixel rotation seed; path tracer: frames accumulated before this one
    float light_map_scale;       // light-map texel footprint scale (shadow resolution / light-map resolution)
    uint bounces;                // path-tracer bounces (0: unbounded, Russian roulette)
    float ray_offset_voxels;     // self-intersection offset along the ray, k2 (voxel diagonals)
    float ray_offset_max_voxels; // its clamp (voxel diagonals)
} gi;
#endif

// Where a ray meets the surface inside the voxel v it entered at parameter t_in: the plane of
// the voxel's owner triangle (voxelize_attributes_resolve.comp stores its world normal in
// nd.xyz and its offset from the voxel centre in nd.w), clamped to the ray's stretch inside the
// voxel. The entry point itself lies up to a voxel diagonal in front of the surface, where
// shadow maps and light samples see a different light than the surface does. o and d are the
// ray's origin and direction in world space and t its parameter there, w2v the grid's
// world-to-voxel transform; voxels without a normal (none stored) keep the entry point.
vec3 voxel_surface_point(mat4 w2v, ivec3 v, vec4 nd, vec3 o, vec3 d, float t_in) {
    if (dot(nd.xyz, nd.xyz) <= 0.25) return o + d * t_in;
    mat3 m = mat3(w2v);
    vec3 ov = (w2v * vec4(o, 1.0)).xyz;
    vec3 dv = m * d;
    // The plane's voxel-space normal: normals transform by the inverse transpose.
    vec3 nv = normalize(transpose(inverse(m)) * nd.xyz);
    vec3 c = vec3(v) + 0.5;
    // The ray's exit from the unit cube of v (a zero direction component taken as 1e-12, so
    // that no 0 * inf makes a NaN).
    vec3 inv = 1.0 / mix(vec3(1e-12), dv, greaterThan(abs(dv), vec3(1e-12)));
    vec3 t0 = (vec3(v) - ov) * inv;
    vec3 t1 = (vec3(v) + 1.0 - ov) * inv;
    vec3 tf = max(t0, t1);
    float t_out = max(min(tf.x, min(tf.y, tf.z)), t_in);
    float den = dot(nv, dv);
    float t = abs(den) > 1e-6 ? (nd.w * 0.8660254 - dot(nv, ov - c)) / den : 0.5 * (t_in + t_out);
    return o + d * clamp(t, t_in, t_out);
}

// Radical inverse in base 2 (Hammersley's second coordinate).
float radical_inverse(uint i) {
    return float(bitfieldReverse(i)) * 2.3283064365386963e-10;
}

// Wang's 32-bit integer hash; every step is invertible, so distinct inputs give distinct
// outputs.
uint wang_hash(uint h) {
    h = (h ^ 61u) ^ (h >> 16u);
    h *= 9u;
    h ^= h >> 4u;
    h *= 0x27d4eb2du;
    h ^= h >> 15u;
    return h;
}

// A per-pixel hash for the Cranley-Patterson rotation (no visible tiling, unlike a small
// random texture).
vec2 pixel_rotation(uvec2 p, uint seed) {
    uint h = wang_hash(p.x * 1973u + p.y * 9277u + seed * 26699u);
    uint h2 = h * 747796405u + 2891336453u;
    return vec2(float(h & 0xffffu), float(h2 >> 16u)) / 65536.0;
}

// Element i of the R2 sequence (Roberts 2018): the additive recurrence by the powers of the
// plastic number's inverse, the 2D low-discrepancy sequence with the best packing. In 32-bit
// fixed point, so that any index keeps full precision.
vec2 r2(uint i) {
    uvec2 a = uvec2(3242174889u, 2447445413u);  // 2^32 / g, 2^32 / g^2, g = 1.3247...
    return vec2(i * a) / 4294967296.0;
}

// Direction at polar cosine `c` and azimuth 2 pi u around the unit axis `a`.
vec3 around_axis(vec3 a, float c, float u) {
    float s = sqrt(max(1.0 - c * c, 0.0));
    float phi = 2.0 * PI * u;
    vec3 t = abs(a.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 b1 = normalize(cross(a, t));
    vec3 b2 = cross(a, b1);
    return normalize(b1 * (s * cos(phi)) + b2 * (s * sin(phi)) + a * c);
}

// Cosine-distributed direction around n (Malley's method): cos theta = sqrt(1 - u).
vec3 cosine_direction(vec3 n, vec2 u) {
    return around_axis(n, sqrt(max(1.0 - u.x, 0.0)), u.y);
}

// Normalized-Phong lobe around the mirror direction r: pdf (n+1)/(2 pi) cos^n alpha, so
// cos alpha = u^(1/(n+1)) (the thesis's printed formula has a square root too many).
vec3 phong_direction(vec3 r, float shininess, vec2 u) {
    return around_axis(r, pow(max(u.x, 1e-30), 1.0 / (shininess + 1.0)), u.y);
}

// Combines the estimates of a pixel: Lambert pixels keep the irradiance E (the filter works
// on irradiance and the composite multiplies by albedo / pi); Phong pixels store their
// indirect radiance, albedo/pi * E plus the lobe estimate rho_s (n+2)/(n+1) * mean(L cos).
bool is_phong_pixel(vec3 specular) { return any(greaterThan(specular, vec3(0.0))); }

#endif

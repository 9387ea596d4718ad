// BRDFs of voxgi (docs/ARCHITECTURE.md, "The path of a frame", step 1).
#ifndef BRDF_GLSL
#define BRDF_GLSL

#define PI 3.14159265358979323846

// Lambert: f = rho / pi.
vec3 brdf_lambert(vec3 albedo) {
    return albedo / PI;
}

// cos^n(alpha) of the Phong lobe, 0 where alpha >= 90 degrees. Not pow(max(c, 0), n): GLSL
// leaves pow(0, n) undefined for n <= 0, and NVIDIA's exp2(n log2 c) returns NaN for pow(0, 0).
// A material without a specular part has n = 0 and rho_s = 0, and 0 * NaN is NaN: on an H200
// (driver 580) every pixel of such a surface that faced away from the mirror direction was NaN
// in any scene that also had a Phong material (lavapipe returns 1 there).
float phong_cos_power(float c, float shininess) {
    return c > 0.0 ? pow(c, shininess) : 0.0;
}

// Normalized Phong (Lafortune & Willems 1994): f = rho_s (n + 2) / (2 pi) cos^n(alpha), alpha the
// angle between the mirror direction of wi and wo.
vec3 brdf_phong(vec3 specular, float shininess, vec3 n, vec3 wi, vec3 wo) {
    vec3 r = reflect(-wi, n);
    return specular * (shininess + 2.0) / (2.0 * PI) * phong_cos_power(dot(r, wo), shininess);
}

// GGX metal/roughness (docs/ARCHITECTURE.md, units; the Rust twin is scene::ggx_brdf), from
// the G-buffer's split: diffuse = (1 - metallic) base, f0 = mix(0.04, base, metallic),
// alpha = roughness^2:
// f = diffuse/pi (1 - F_d(n.wi)) (1 - F_d(n.wo)) + D(h) G1(wi) G1(wo) F(wo.h) / (4 (n.wi)(n.wo)),
// D GGX, G1 exact Smith-GGX, F Schlick with f0, F_d Schlick with 0.04.
float ggx_d(float alpha, float n_dot_h) {
    float a2 = alpha * alpha;
    float t = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

float ggx_g1(float alpha, float c) {
    float a2 = alpha * alpha;
    return 2.0 * c / max(c + sqrt(a2 + (1.0 - a2) * c * c), 1e-30);
}

vec3 fresnel_schlick(vec3 f0, float c) {
    return f0 + (1.0 - f0) * pow(1.0 - clamp(c, 0.0, 1.0), 5.0);
}

// 1 - F_d(c): the weight of the GGX diffuse lobe on one side (Schlick with F0 = 0.04).
float ggx_diffuse_weight(float c) {
    return 1.0 - fresnel_schlick(vec3(0.04), c).x;
}

// The specular lobe of brdf_ggx, D(h) G1(wi) G1(wo) F(wo.h) / (4 (n.wi)(n.wo)); 0 below
// either horizon.
vec3 brdf_ggx_specular(vec3 f0, float roughness, vec3 n, vec3 wi, vec3 wo) {
    float ci = dot(n, wi);
    float co = dot(n, wo);
    if (ci <= 0.0 || co <= 0.0) return vec3(0.0);
    float alpha = roughness * roughness;
    vec3 h = normalize(wi + wo);
    return fresnel_schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * ggx_g1(alpha, ci)
        * ggx_g1(alpha, co) / (4.0 * ci * co));
}

vec3 brdf_ggx(vec3 diffuse, vec3 f0, float roughness, vec3 n, vec3 wi, vec3 wo) {
    float ci = dot(n, wi);
    float co = dot(n, wo);
    if (ci <= 0.0 || co <= 0.0) return vec3(0.0);
    return diffuse * (ggx_diffuse_weight(ci) * ggx_diffuse_weight(co) / PI)
        + brdf_ggx_specular(f0, roughness, n, wi, wo);
}

#endif

// A surface point's material as the path tracer samples it, at the G-buffer point and at every
// voxel hit (docs/ARCHITECTURE.md, "Materials"): Lambert, normalized Phong or GGX
// metal/roughness, one sampling function for both places. Needs brdf.glsl and gi_common.glsl
// (cosine_direction, phong_direction).
#ifndef MATERIAL_LOBE_GLSL
#define MATERIAL_LOBE_GLSL

const uint LOBE_LAMBERT = 0u;
const uint LOBE_PHONG = 1u;
const uint LOBE_GGX = 2u;

struct Lobe {
    uint kind;
    vec3 diffuse;   // Lambert albedo, Phong rho_d, GGX (1 - m) b
    vec3 specular;  // Phong rho_s, GGX F0 = mix(0.04, b, m); unused for Lambert
    float param;    // Phong exponent n, GGX perceptual roughness r
};

Lobe lambert_lobe(vec3 albedo) {
    return Lobe(LOBE_LAMBERT, albedo, vec3(0.0), 0.0);
}

// The material volume's texel (src/voxel/attributes.rs, `material_texel`) with the albedo
// volume's value at the same voxel (the base color of GGX materials): w = 0 Lambert;
// w >= 1 Phong with rgb = rho_s and exponent w - 1; w = -1 GGX with rgb = (r, m, 0).
Lobe voxel_lobe(vec3 albedo, vec4 t) {
    if (t.w >= 0.5) return Lobe(LOBE_PHONG, albedo, t.rgb, t.w - 1.0);
    if (t.w <= -0.5) {
        float m = clamp(t.g, 0.0, 1.0);
        return Lobe(LOBE_GGX, (1.0 - m) * albedo, mix(vec3(0.04), albedo, m), clamp(t.r, 0.0, 1.0));
    }
    return lambert_lobe(albedo);
}

// The GGX width alpha = r^2, kept off 0 where sampling divides by it.
float lobe_alpha(Lobe m) {
    return max(m.param * m.param, 1e-4);
}

// f(wi, wo) (wo toward the viewer, both on n's side) for next event estimation.
vec3 lobe_brdf(Lobe m, vec3 n, vec3 wi, vec3 wo) {
    if (m.kind == LOBE_PHONG) return brdf_lambert(m.diffuse) + brdf_phong(m.specular, m.param, n, wi, wo);
    if (m.kind == LOBE_GGX) return brdf_ggx(m.diffuse, m.specular, sqrt(lobe_alpha(m)), n, wi, wo);
    return brdf_lambert(m.diffuse);
}

// A GGX microfacet normal seen from wo (n the z axis), distributed as the visible normals
// D_wo(h) = G1(wo) max(0, wo.h) D(h) / (n.wo) (Heitz 2018, "Sampling the GGX Distribution of
// Visible Normals", listing 1). Reflecting wo about h then gives wi with the exact weight
// f_spec (n.wi) / pdf(wi) = F(wo.h) G1(wi) for the separable Smith G = G1(wi) G1(wo).
vec3 ggx_visible_normal(vec3 n, vec3 wo, float alpha, vec2 u) {
    vec3 t = abs(n.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 b1 = normalize(cross(n, t));
    vec3 b2 = cross(n, b1);
    vec3 v = vec3(dot(wo, b1), dot(wo, b2), dot(wo, n));
    vec3 vh = normalize(vec3(alpha * v.x, alpha * v.y, v.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float s = 0.5 * (1.0 + vh.z);
    float p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    vec3 h = normalize(vec3(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    return normalize(b1 * h.x + b2 * h.y + n * h.z);
}

// The probability that a path leaving a voxel hit takes the specular lobe: 1/2 for Phong and
// GGX (the first bounce's split, drawn at random instead of stratified), 1 for a black
// diffuse part (metals), 0 for Lambert.
float lobe_specular_probability(Lobe m) {
    if (m.kind == LOBE_LAMBERT) return 0.0;
    return all(equal(m.diffuse, vec3(0.0))) ? 1.0 : 0.5;
}

// A direction wi from a point of material m (normal n, wo toward the viewer) sampled from the
// specular lobe (`specular`) or the cosine-weighted diffuse lobe, and in `weight` that lobe's
// f cos / pdf with the lobe's own pdf; diffuse samples leave out the diffuse color (Lambert
// pixels store irradiance, the caller multiplies it in):
//   diffuse: 1; GGX (1 - F_d(n.wi)) (1 - F_d(n.wo))
//   Phong lobe (pdf (n+1)/(2 pi) cos^n about the mirror direction): rho_s (n+2)/(n+1) (n.wi)
//   GGX lobe (visible normals, Heitz 2018): F(wo.h) G1(wi) for the separable Smith G.
// A sample below the surface gets weight 0.
vec3 sample_lobe(Lobe m, vec3 n, vec3 wo, bool specular, vec2 u, out vec3 weight) {
    vec3 wi;
    if (specular && m.kind == LOBE_GGX) {
        vec3 h = ggx_visible_normal(n, wo, lobe_alpha(m), u);
        wi = reflect(-wo, h);
        float ci = dot(n, wi);
        weight = ci > 0.0 ? fresnel_schlick(m.specular, dot(wo, h)) * ggx_g1(lobe_alpha(m), ci) : vec3(0.0);
    } else if (specular && m.kind == LOBE_PHONG) {
        wi = phong_direction(reflect(-wo, n), m.param, u);
        float ci = dot(n, wi);
        weight = ci > 0.0 ? m.specular * ((m.param + 2.0) / (m.param + 1.0) * ci) : vec3(0.0);
    } else {
        wi = cosine_direction(n, u);
        weight = vec3(1.0);
        if (m.kind == LOBE_GGX) {
            float fdi = 1.0 - fresnel_schlick(vec3(0.04), dot(n, wi)).x;
            float fdo = 1.0 - fresnel_schlick(vec3(0.04), max(dot(n, wo), 0.0)).x;
            weight = vec3(fdi * fdo);
        }
    }
    return wi;
}

// The density (per solid angle) with which sample_lobe(m, n, wo, specular, ...) draws wi, for
// multiple importance sampling against light samples (emitters.glsl):
//   diffuse: (n.wi)/pi (Malley's method)
//   Phong lobe: (n+1)/(2 pi) cos^n alpha about the mirror direction of wo
//   GGX lobe: D_wo(h) / (4 wo.h) = G1(wo) D(h) / (4 n.wo) (Heitz 2018, eq. 17 and the
//   reflection Jacobian 1/(4 wo.h)).
float lobe_pdf(Lobe m, vec3 n, vec3 wo, vec3 wi, bool specular) {
    if (specular && m.kind == LOBE_GGX) {
        float co = dot(n, wo);
        vec3 h = normalize(wi + wo);
        if (co <= 0.0 || dot(wo, h) <= 0.0) return 0.0;
        float alpha = lobe_alpha(m);
        return ggx_g1(alpha, co) * ggx_d(alpha, max(dot(n, h), 0.0)) / (4.0 * co);
    }
    if (specular && m.kind == LOBE_PHONG) {
        // phong_cos_power, not pow(max(c, 0), n): the metals of an MTL without `Ns` have
        // n = 0, and NVIDIA's pow(0, 0) is NaN (it poisoned the Modern Hall's path tracer).
        return (m.param + 1.0) / (2.0 * PI) * phong_cos_power(dot(reflect(-wo, n), wi), m.param);
    }
    return max(dot(n, wi), 0.0) / PI;
}

// The part of lobe_brdf that sample_lobe's `specular` choice samples: f cos / lobe_pdf is the
// weight sample_lobe returns (times m.diffuse for diffuse samples, which it leaves out).
vec3 lobe_part_brdf(Lobe m, vec3 n, vec3 wi, vec3 wo, bool specular) {
    if (specular) {
        if (m.kind == LOBE_PHONG) return brdf_phong(m.specular, m.param, n, wi, wo);
        if (m.kind == LOBE_GGX) return brdf_ggx_specular(m.specular, sqrt(lobe_alpha(m)), n, wi, wo);
        return vec3(0.0);
    }
    vec3 f = brdf_lambert(m.diffuse);
    if (m.kind == LOBE_GGX) {
        f *= ggx_diffuse_weight(max(dot(n, wi), 0.0)) * ggx_diffuse_weight(max(dot(n, wo), 0.0));
    }
    return f;
}

#endif

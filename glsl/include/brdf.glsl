// BRDFs of voxgi (docs/ARCHITECTURE.md, "The path of a frame", step 1).
#ifndef BRDF_GLSL
#define BRDF_GLSL

#define PI 3.14159265358979323846

// Lambert: f = rho / pi.
vec3 brdf_lambert(vec3 albedo) {
    return albedo / PI;
}

// Normalized Phong (Lafortune & Willems 1994): f = rho_s (n + 2) / (2 pi) cos^n(alpha), alpha the
// angle between the mirror direction of wi and wo.
vec3 brdf_phong(vec3 specular, float shininess, vec3 n, vec3 wi, vec3 wo) {
    vec3 r = reflect(-wi, n);
    float c = max(dot(r, wo), 0.0);
    return specular * (shininess + 2.0) / (2.0 * PI) * pow(c, shininess);
}

#endif

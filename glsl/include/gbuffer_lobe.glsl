// Reading the G-buffer's specular-lobe target (gbuffer.frag): rgb is the Phong reflectance
// rho_s or the GGX F0, alpha the lobe kind (1 Phong, 2 GGX).
#ifndef GBUFFER_LOBE_GLSL
#define GBUFFER_LOBE_GLSL

// The Phong reflectance at px; zero for GGX pixels, which the GI methods read from the texel
// itself (alpha 2: F0 in rgb, the roughness in the normal target's w).
vec3 gbuffer_phong_specular(sampler2D lobe, ivec2 px) {
    vec4 v = texelFetch(lobe, px, 0);
    return v.a < 1.5 ? v.rgb : vec3(0.0);
}

#endif

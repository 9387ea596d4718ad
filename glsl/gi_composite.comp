#version 450
// Direct plus indirect light: L = L_direct + rho/pi * E_indirect for Lambert receivers; Phong
// and GGX receivers' indirect radiance is stored as is (see gi_common.glsl).
// With SAO (Oetke 2017 §2.5) the indirect term is multiplied by the AO term (computed at half
// resolution, joint-bilaterally upsampled to the frame by sao_upsample); SAO_VIEW writes the AO
// term itself as grey radiance (`--sao-show`).
layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_SAO = false;
layout(constant_id = 2) const bool SAO_VIEW = false;
// Every method stores GGX pixels' indirect radiance too (their whole BRDF: the lobe sampled by
// the hemisphere rays and the path tracer's first bounce, evaluated toward each VPL, Eq. 2.19's
// split sum in screen space); set in every scene with GGX materials.
layout(constant_id = 3) const bool GGX_RADIANCE = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D direct;
layout(set = 0, binding = 1) uniform sampler2D gb_albedo;
layout(set = 0, binding = 2) uniform sampler2D indirect_irradiance;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D radiance;
layout(set = 0, binding = 4) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 5) uniform sampler2D sao;           // albedo when !HAS_SAO
#include "gbuffer_lobe.glsl"

#define PI 3.14159265358979323846

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec4 d = texelFetch(direct, p, 0);
    vec3 albedo = texelFetch(gb_albedo, p, 0).rgb;
    vec3 e = texelFetch(indirect_irradiance, p, 0).rgb;
    // Phong pixels already hold their indirect radiance (see gi_common.glsl).
    bool phong = HAS_PHONG && any(greaterThan(gbuffer_phong_specular(gb_specular, p), vec3(0.0)));
    phong = phong || (GGX_RADIANCE && texelFetch(gb_specular, p, 0).a > 1.5);
    float ao = HAS_SAO ? texelFetch(sao, p, 0).r : 1.0;
    if (SAO_VIEW) {
        imageStore(radiance, p, vec4(vec3(ao), d.a));
        return;
    }
    imageStore(radiance, p, vec4(d.rgb + ao * (phong ? e : albedo / PI * e), d.a));
}

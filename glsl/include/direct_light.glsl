// Direct light at a surface point from every light of the frame, with shadow-map visibility:
// the outgoing radiance (W/(m^2 sr)) toward wo. Shared by the deferred pass (deferred_direct.comp)
// and the transparent layers (oit_gather.frag), so both shade a material the same way.
// Lambert f = rho/pi; normalized Phong only when HAS_PHONG, GGX only when HAS_GGX (the includer
// declares both constants, `frame` and includes brdf.glsl and shadow.glsl first).
// Point/spot: E = I cos(theta) / d^2 times Mitsuba's spot falloff; directional:
// E = E_perp cos(theta).
#ifndef DIRECT_LIGHT_GLSL
#define DIRECT_LIGHT_GLSL

// `lobe`: rgb Phong rho_s or GGX F0, a the lobe kind (1 Phong, 2 GGX; 0 none);
// `lobe_parameter`: the Phong exponent or the GGX roughness (gbuffer.frag has the encoding).
vec3 direct_radiance(sampler2DArray shadow_maps, vec3 p, vec3 n, vec3 wo, vec3 albedo, vec4 lobe,
                     float lobe_parameter) {
    vec3 specular = lobe.rgb;
    bool ggx = HAS_GGX && lobe.a > 1.5;
    vec3 lo = vec3(0.0);
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight l = frame.lights[i];
        vec3 wi;
        vec3 e;
        if (l.info.x == LIGHT_DIRECTIONAL) {
            wi = -l.direction.xyz;
            e = l.intensity.rgb * max(dot(n, wi), 0.0);
        } else {
            vec3 d = l.position.xyz - p;
            float d2 = max(dot(d, d), 1e-30);
            wi = d * inversesqrt(d2);
            float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
            e = l.intensity.rgb * (falloff * max(dot(n, wi), 0.0) / d2);
        }
        if (all(equal(e, vec3(0.0)))) continue;
        float vis = direct_shadow_visibility(shadow_maps, l, p, n, max(dot(n, wi), 0.0));
        vec3 f;
        if (ggx) {
            f = brdf_ggx(albedo, specular, lobe_parameter, n, wi, wo);
        } else {
            f = brdf_lambert(albedo);
            if (HAS_PHONG) f += brdf_phong(specular, lobe_parameter, n, wi, wo);
        }
        lo += f * e * vis;
    }
    return lo;
}

#endif

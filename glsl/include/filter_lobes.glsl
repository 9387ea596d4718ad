// The lobe rules the indirect light's spatial filters share (gi_filter.comp, gi_svgf.comp): in
// scenes with Phong or GGX materials the G-buffer's lobe target says which kind of lobe a pixel
// has, and its normal target's w the lobe's sharpness. A pixel averages only pixels of its own
// lobe kind (Lambert irradiance never mixes with glossy radiance), and a glossy pixel only
// neighbours whose mirror directions lie within its lobe.

// The lobe kind of the lobe target's texel: 0 Lambert, 1 Phong (rho_s > 0), 2 GGX.
int lobe_kind(vec4 t) {
    if (t.a > 1.5) return 2;
    return any(greaterThan(t.rgb, vec3(0.0))) ? 1 : 0;
}

// The half-maximum angle of a lobe about its mirror direction (kind 1 or 2; w the normal
// target's w: the Phong exponent or the GGX roughness).
float lobe_half_angle(int kind, float w) {
    float n = w;
    if (kind == 2) {
        float alpha = max(w * w, 1e-4);
        n = 2.0 / (alpha * alpha) - 2.0;
    }
    return acos(exp2(-1.0 / max(n, 1e-3)));
}

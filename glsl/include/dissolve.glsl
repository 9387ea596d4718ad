// MTL `d` (dissolve) as coverage: a fragment of a material with opacity a survives with
// probability a, so that a region's mean is a * front + (1 - a) * behind, in the G-buffer and
// in every shadow map (partial shadows). Hashed alpha testing (Wyman and McGuire 2017, "Hashed
// Alpha Testing", listings 1 and 3): the threshold is a hash of the surface position quantized
// at about the pixel's footprint, blended between the two neighbouring power-of-two scales and
// remapped so it stays uniform in (0, 1]. The pattern sticks to the surface as the camera moves
// (unlike screen-space dither), and two stacked surfaces get independent patterns. Positions
// are world-space (a rigid frame of it in the paraboloid maps): on moving objects the pattern
// slides.
#ifndef DISSOLVE_GLSL
#define DISSOLVE_GLSL

float dissolve_hash2(vec2 v) {
    return fract(1.0e4 * sin(17.0 * v.x + 0.1 * v.y) * (0.1 + abs(sin(13.0 * v.y + v.x))));
}

float dissolve_hash3(vec3 v) {
    return dissolve_hash2(vec2(dissolve_hash2(v.xy), v.z));
}

// Threshold in (0, 1] for the fragment at position p (any rigid frame, meters). Call it in
// uniform control flow (it takes derivatives), before any discard.
float dissolve_threshold(vec3 p) {
    float max_deriv = max(max(length(dFdx(p)), length(dFdy(p))), 1e-30);
    float pix_scale = 1.0 / max_deriv;
    float l = log2(pix_scale);
    vec2 scales = vec2(exp2(floor(l)), exp2(ceil(l)));
    vec2 hashes = vec2(dissolve_hash3(floor(scales.x * p)), dissolve_hash3(floor(scales.y * p)));
    float t = fract(l);
    float x = mix(hashes.x, hashes.y, t);
    // The blend of two uniform hashes is not uniform; this CDF maps it back (listing 3).
    float a = min(t, 1.0 - t);
    vec3 cases = vec3(x * x / (2.0 * a * (1.0 - a)), (x - 0.5 * a) / (1.0 - a),
                      1.0 - (1.0 - x) * (1.0 - x) / (2.0 * a * (1.0 - a)));
    float threshold = x < 1.0 - a ? (x < a ? cases.x : cases.y) : cases.z;
    return clamp(threshold, 1.0e-6, 1.0);
}

#endif

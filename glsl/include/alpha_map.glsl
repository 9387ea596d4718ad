// Per-texel alpha of a material (`AlphaMap`, src/scene/material.rs): the alpha channel of the
// draw's texture (the albedo map, or the alpha map of a material without one). GpuMaterial's
// flags.w holds f32 bits: 0 none; a cutoff c in (0, 1] for a cutout, the surface absent where
// the texel's alpha is below c (glTF 2.0 §3.9.4, alphaMode MASK; MTL map_d at c = 0.5); -1 for
// per-texel opacity, the material's opacity times the alpha (alphaMode BLEND).
#ifndef ALPHA_MAP_GLSL
#define ALPHA_MAP_GLSL

// The fragment's opacity: `opacity` (GpuMaterial albedo.a) times the texel's alpha for a blend
// map; 0 where a cutout map cuts the surface away, else `opacity`.
float alpha_map_opacity(uint flag, float opacity, float texel_alpha) {
    float mode = uintBitsToFloat(flag);
    if (mode < 0.0) return opacity * texel_alpha;
    if (mode > 0.0 && texel_alpha < mode) return 0.0;
    return opacity;
}

// The opacity below which a fragment is discarded: the hashed threshold of dissolve.glsl where
// some material is partly transparent, else anything above 0 (cut-away fragments have opacity
// exactly 0, every other fragment of an opaque pass opacity 1).
float alpha_map_keep_threshold(bool dissolve, float dissolve_threshold) {
    return dissolve ? dissolve_threshold : 0.5;
}

#endif

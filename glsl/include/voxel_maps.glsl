// The MTL texture maps (map_Kd, map_Pr, map_Pm, map_Ke) as the voxelizers and the VPL emitter
// rays read them (src/voxel/maps.rs):
// every map's mip chain in one storage buffer, each texel linear RGBA as two packHalf2x16
// words (sRGB maps decoded on the CPU: no pow per lookup), and a table row per scene texture
// (x: index of its first texel, y: width, z: height, w: levels), so one dispatch or draw
// samples the maps of every material without a descriptor per texture. The includer defines
// VOXEL_MAPS_TEXELS_BINDING and VOXEL_MAPS_TABLE_BINDING.
//
// Per triangle (GpuTriangleMaps): uv01 = (uv0, uv1), uv2_lod = (uv2, lod, 0) with lod the log2
// of the sample spacing in texture-coordinate units (add log2 of the map's size for texels),
// maps = (roughness, metallic, emission, albedo) texture indices, -1 where the triangle reads
// none.
#ifndef VOXEL_MAPS_GLSL
#define VOXEL_MAPS_GLSL

layout(set = 0, binding = VOXEL_MAPS_TEXELS_BINDING, std430) readonly buffer VoxelMapTexels {
    uint map_texels[];
};
layout(set = 0, binding = VOXEL_MAPS_TABLE_BINDING, std430) readonly buffer VoxelMapTable {
    uvec4 map_table[];
};

// Texel p >= 0 (wrapped: the G-buffer's sampler repeats) of the level starting at `base`.
vec4 voxel_map_texel(uint base, ivec2 size, ivec2 p) {
    p = ivec2(uvec2(max(p, ivec2(0))) % uvec2(size));
    uint i = 2u * (base + uint(p.y * size.x + p.x));
    return vec4(unpackHalf2x16(map_texels[i]), unpackHalf2x16(map_texels[i + 1u]));
}

// Map `map` at texture coordinate uv (OBJ's v up, as the meshes store it) over a footprint of
// 2^lod texels of level 0: bilinear in the level nearest that footprint (the box-filtered
// chain of TextureData::mip_chain, the G-buffer's levels), blending linear values as a
// sampler of an sRGB image does.
vec4 sample_voxel_map(int map, vec2 uv, float lod) {
    uvec4 m = map_table[map];
    int levels = int(m.w);
    ivec2 size = ivec2(m.yz);
    float l = lod + 0.5 * log2(float(size.x) * float(size.y));
    int level = clamp(int(floor(l + 0.5)), 0, max(levels - 1, 0));
    uint base = m.x;
    for (int i = 0; i < level; i++) {
        base += uint(size.x * size.y);
        size = max(size / 2, ivec2(1));
    }
    // Image rows start at the top; texel centres at half-integers.
    vec2 st = vec2(uv.x, 1.0 - uv.y) * vec2(size) - 0.5;
    if (any(isnan(st)) || any(isinf(st))) st = vec2(0.0);
    st -= vec2(size) * floor(st / vec2(size));
    ivec2 p = ivec2(floor(st));
    vec2 f = st - floor(st);
    vec4 a = mix(voxel_map_texel(base, size, p), voxel_map_texel(base, size, p + ivec2(1, 0)), f.x);
    vec4 b = mix(voxel_map_texel(base, size, p + ivec2(0, 1)), voxel_map_texel(base, size, p + ivec2(1, 1)), f.x);
    return mix(a, b, f.y);
}

// The texture coordinate at barycentric weights w of the triangle whose row is (uv01, uv2_lod).
vec2 voxel_map_uv(vec4 uv01, vec4 uv2_lod, vec3 w) {
    return w.x * uv01.xy + w.y * uv01.zw + w.z * uv2_lod.xy;
}

#endif

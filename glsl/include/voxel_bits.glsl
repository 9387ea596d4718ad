// Binary voxel columns (docs/ARCHITECTURE.md, "The voxel representation";
// src/voxel/bits.rs is the CPU twin).
// Depth index k counts from the voxel camera's near plane: layer = k / 128,
// channel = (k mod 128) / 32, bit = k mod 32, least significant bit = nearest.
#ifndef VOXEL_BITS_GLSL
#define VOXEL_BITS_GLSL

#define VOXEL_COLUMN_BITS 128u

uint voxel_layer(uint k) { return k >> 7; }
uint voxel_channel(uint k) { return (k >> 5) & 3u; }
uint voxel_bit(uint k) { return k & 31u; }

// Index of the u32 word holding voxel (xy, k) in a column buffer laid out like a tightly
// packed read-back of mip 0 of the R32G32B32A32_UINT array image: layer, row, x, channel.
// `extent` is the image's (width, height).
uint voxel_word_index(uvec2 xy, uint k, uvec2 extent) {
    return ((voxel_layer(k) * extent.y + xy.y) * extent.x + xy.x) * 4u + voxel_channel(k);
}

#endif

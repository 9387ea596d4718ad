#version 450
// Material volume congruent with the bit grid, only in scenes with Phong or GGX materials whose
// path tracer samples lobes at every bounce: per voxel the specular lobe of its owner triangle,
// encoded as src/voxel/attributes.rs's `material_texel` and decoded by
// glsl/include/material_lobe.glsl's `voxel_lobe`. The writing is voxelize_owner_value.glsl's.
#include "voxelize_owner_value.glsl"

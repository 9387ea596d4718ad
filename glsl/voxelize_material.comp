#version 450
// Material volume congruent with the bit grid, only in scenes with Phong or GGX materials whose
// path tracer samples lobes at every bounce: per voxel the specular lobe of its owner triangle,
// encoded as src/voxel/attributes.rs's `material_texel` and decoded by
// glsl/include/material_lobe.glsl's `voxel_lobe`, with map_Pr / map_Pm sampled over the owner's
// part of the voxel (HAS_MAPS). The writing is voxelize_owner_value.glsl's.
#define OWNER_VALUE_MATERIAL
#include "voxelize_owner_value.glsl"

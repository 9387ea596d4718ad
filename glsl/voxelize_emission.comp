#version 450
// Emission volume congruent with the bit grid, only in scenes with emitters: per voxel the
// emitted radiance (rgb W/(m^2 sr), leaving the side the face normal points to; w 0) of its
// owner triangle, with map_Ke sampled over the owner's part of the voxel (HAS_MAPS). The
// writing is voxelize_owner_value.glsl's.
#define OWNER_VALUE_EMISSION
#include "voxelize_owner_value.glsl"

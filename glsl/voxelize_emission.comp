#version 450
// Emission volume congruent with the bit grid, only in scenes with emitters: per voxel the
// emitted radiance (rgb W/(m^2 sr), leaving the side the face normal points to; w 0) of its
// owner triangle. The writing is voxelize_owner_value.glsl's.
#include "voxelize_owner_value.glsl"

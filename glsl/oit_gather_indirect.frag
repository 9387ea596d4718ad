#version 450
// Transparent layers into per-pixel lists, shaded with direct light, emission and the voxel
// path tracer's indirect light (include/oit_gather_body.glsl, VOXEL_INDIRECT).
#define VOXEL_INDIRECT
#include "oit_gather_body.glsl"

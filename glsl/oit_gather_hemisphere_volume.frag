#version 450
// Transparent layers into per-pixel lists, shaded with direct light, emission and the
// hemisphere method's one bounce, radiance at hits from the direct-radiance voxel volume
// (include/oit_gather_body.glsl, HEMISPHERE_INDIRECT).
#define HEMISPHERE_INDIRECT
#define RADIANCE_FROM_VOLUME
#include "oit_gather_body.glsl"

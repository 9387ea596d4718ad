#version 450
// Transparent layers into per-pixel lists, shaded with direct light, emission and the
// hemisphere method's one bounce, radiance at hits from the reflective light maps
// (include/oit_gather_body.glsl, HEMISPHERE_INDIRECT).
#define HEMISPHERE_INDIRECT
#include "oit_gather_body.glsl"

#version 450
// Transparent layers into per-pixel lists, shaded with direct light, emission and the
// hemisphere method's one bounce, radiance at hits from the reflective light maps plus the
// emitters' from the emission volume (include/oit_gather_body.glsl, HEMISPHERE_INDIRECT).
#define HEMISPHERE_INDIRECT
#define EMISSION_FROM_VOLUME
#include "oit_gather_body.glsl"

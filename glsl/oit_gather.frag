#version 450
// Transparent layers into per-pixel lists, shaded with direct light and emission
// (include/oit_gather_body.glsl).
#include "oit_gather_body.glsl"

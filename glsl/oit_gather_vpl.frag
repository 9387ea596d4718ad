#version 450
// Transparent layers into per-pixel lists, shaded with direct light, emission and the frame's
// virtual point lights, every interleaved set (include/oit_gather_body.glsl, VPL_INDIRECT).
#define VPL_INDIRECT
#include "oit_gather_body.glsl"

#version 450
// VPL shading by additive splatting, one pass per VPL of the row (Thiedemann 2010, §7.3); see
// include/gi_vpl_gather_body.glsl.
#define VPL_SPLAT
#include "gi_vpl_gather_body.glsl"

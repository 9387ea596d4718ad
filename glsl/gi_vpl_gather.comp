#version 450
// VPL shading, every VPL of a pixel's set in one loop (Thiedemann 2010, §7.3); see
// include/gi_vpl_gather_body.glsl.
#include "gi_vpl_gather_body.glsl"

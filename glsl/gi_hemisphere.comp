#version 450
// Hemisphere sampling with radiance at hits from the reflective light maps (§6.1, §6.2).
#include "gi_hemisphere_body.glsl"

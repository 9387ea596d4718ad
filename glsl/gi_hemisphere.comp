#version 450
// Hemisphere sampling with radiance at hits from the reflective light maps (Thiedemann 2010, §6.3.3, §6.4.1).
#include "gi_hemisphere_body.glsl"

#version 450
// Hemisphere sampling with radiance at hits from the reflective light maps plus, in scenes with
// emitters, the emitted radiance from the emission volume (Thiedemann 2010, §6.3.3, §6.4.1).
#define EMISSION_FROM_VOLUME
#include "gi_hemisphere_body.glsl"

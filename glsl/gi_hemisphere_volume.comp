#version 450
// Hemisphere sampling with radiance at hits from the direct-radiance voxel volume (the
// thesis's alternative to light maps for diffuse senders).
#define RADIANCE_FROM_VOLUME
#include "gi_hemisphere_body.glsl"

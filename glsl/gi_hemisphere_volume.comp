#version 450
// Hemisphere sampling with radiance at hits from the direct-radiance voxel volume (the
// thesis's alternative to light maps for diffuse senders); a glossy sender adds its specular
// lobe toward the ray at the hit (gi_hemisphere_body.glsl, hit_radiance).
#define RADIANCE_FROM_VOLUME
#include "gi_hemisphere_body.glsl"

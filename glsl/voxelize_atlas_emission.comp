#version 450
// Resolves the atlas emission sums (voxelize_atlas_volumes.frag) into the emission volume the
// path tracer and the radiance volume read: the mean radiance of the emitters' points in each
// voxel (emitters own the voxels they share, as in the triangle voxelizer's order: a light
// patch just under a ceiling emits from the voxels it shares with the ceiling; a map's black
// texels are still the emitter's), 0 where none landed. Static sums + this frame's, as
// voxelize_atlas_resolve.comp; every voxel is written.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler2DArray static_emission;   // rgb sum, a = count
layout(set = 0, binding = 1) uniform sampler2DArray frame_emission;
layout(set = 0, binding = 2, rgba16f) uniform writeonly image3D emission_volume;

layout(push_constant) uniform Push {
    uvec4 dims;   // res_x, res_y, D; w: bit 0 = static sums bound, bit 1 = frame sums bound
} pc;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(uvec3(v), pc.dims.xyz))) {
        return;
    }
    vec4 e = vec4(0.0);
    if ((pc.dims.w & 1u) != 0u) e += texelFetch(static_emission, v, 0);
    if ((pc.dims.w & 2u) != 0u) e += texelFetch(frame_emission, v, 0);
    imageStore(emission_volume, v, e.w > 0.0 ? vec4(e.rgb / e.w, 0.0) : vec4(0.0));
}

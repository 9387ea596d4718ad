#version 450
// Emission volume congruent with the bit grid, only in scenes with emitters (between steps 1 and
// 2 of the albedo and normal volumes, see voxelize_attributes.comp): every voxel a triangle
// touched takes the emitted radiance (W/(m^2 sr), leaving the side the face normal points to) of
// the same owner triangle whose albedo and normal voxelize_attributes_resolve.comp stores, so the
// three volumes agree voxel by voxel. Other voxels keep their values.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) readonly buffer Emissions { vec4 emission[]; };  // per triangle
layout(set = 0, binding = 1, r32ui) uniform readonly uimage3D owner_volume;
layout(set = 0, binding = 2, rgba16f) uniform writeonly image3D emission_volume;

const uint NO_OWNER = 0xffffffffu;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, imageSize(owner_volume)))) {
        return;
    }
    uint owner = imageLoad(owner_volume, v).x;
    if (owner == NO_OWNER) {
        return;
    }
    imageStore(emission_volume, v, vec4(emission[owner].rgb, 0.0));
}

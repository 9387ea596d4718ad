// A per-triangle value into a volume congruent with the bit grid, between steps 1 and 2 of the
// albedo and normal volumes (see voxelize_attributes.comp): every voxel a triangle touched takes
// the value of the same owner triangle whose albedo and normal voxelize_attributes_resolve.comp
// stores, so the volumes agree voxel by voxel. Other voxels keep their values. Included by
// voxelize_emission.comp and voxelize_material.comp, which differ only in what the value means.
#ifndef VOXELIZE_OWNER_VALUE_GLSL
#define VOXELIZE_OWNER_VALUE_GLSL

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) readonly buffer Values { vec4 values[]; };  // per triangle
layout(set = 0, binding = 1, r32ui) uniform readonly uimage3D owner_volume;
layout(set = 0, binding = 2, rgba16f) uniform writeonly image3D value_volume;

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
    imageStore(value_volume, v, values[owner]);
}

#endif

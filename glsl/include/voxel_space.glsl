// World point -> continuous voxel coordinates (VoxelGrid::world_to_voxel), for the shaders
// whose push constants `pc` are voxelize_triangles.comp's (grid_min, scale, dims with the
// depth axis in w): the voxelizers (voxelize_core.glsl) and the attribute resolve.
#ifndef VOXEL_SPACE_GLSL
#define VOXEL_SPACE_GLSL

vec3 to_voxel(vec3 p) {
    precise vec3 d = p - pc.grid_min.xyz;
    vec3 f = pc.dims.w == 0u ? d.yzx : (pc.dims.w == 1u ? d.zxy : d);
    precise vec3 r = f * pc.scale.xyz;
    return r;
}

#endif

// The voxel of an atlas point: model space -> world (the object's model matrix) -> the voxel
// camera's frame (VoxelGrid::world_to_voxel) -> floor. Shared by voxelize_atlas.comp (bits)
// and voxelize_atlas_volumes.vert (albedo and normal volumes) so both pick the same voxel for
// every point: every value is `precise` and the matrix product is spelled out in one order,
// so no stage may fuse or reorder differently (Vulkan rounds +, -, * correctly), and the
// volumes stay congruent with the bits (docs/ARCHITECTURE.md, "The voxel representation").
#ifndef ATLAS_VOXEL_GLSL
#define ATLAS_VOXEL_GLSL

// False for points outside the grid: they are clipped, not wrapped.
bool atlas_point_voxel(mat4 model, vec3 p, vec3 grid_min, vec3 scale, uvec4 dims,
                       out uvec3 voxel) {
    precise vec3 world = model[0].xyz * p.x + model[1].xyz * p.y + model[2].xyz * p.z
                       + model[3].xyz;
    precise vec3 d = world - grid_min;
    vec3 f = dims.w == 0u ? d.yzx : (dims.w == 1u ? d.zxy : d);
    precise vec3 s = f * scale;
    vec3 v = floor(s);
    voxel = uvec3(0u);
    if (any(lessThan(v, vec3(0.0))) || any(greaterThanEqual(v, vec3(dims.xyz)))) {
        return false;
    }
    voxel = uvec3(v);
    return true;
}

#endif

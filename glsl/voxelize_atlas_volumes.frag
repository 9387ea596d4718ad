#version 450
// Additive blending sums, per voxel, (albedo, 1) and the unit normals of every point in it;
// voxelize_atlas_resolve.comp divides. Each point stands for the same surface area (atlas
// texels have one size in meters per atlas), so the result is the area-weighted mean, and
// alpha (the point count) is > 0 exactly where a bit is set.
layout(location = 0) flat in vec3 g_albedo;
layout(location = 1) flat in vec3 g_normal;
layout(location = 0) out vec4 o_albedo_weight;
layout(location = 1) out vec4 o_normal_sum;

void main() {
    o_albedo_weight = vec4(g_albedo, 1.0);
    o_normal_sum = vec4(g_normal, 0.0);
}

#version 450
// Additive blending sums, per voxel, (albedo, 1) and the unit normals of every point in it;
// voxelize_atlas_resolve.comp divides. Each point stands for the same surface area (atlas
// texels have one size in meters per atlas), so the result is the area-weighted mean, and
// alpha (the point count) is > 0 exactly where a bit is set. The normal sums' w counts the
// Phong and GGX points. With value volumes (attachments exist only for what the frame has;
// location 2 holds the emission sums, or the material sums without emission, 3 the material
// sums when both exist): (emitted radiance, 1) of emitters' points (voxelize_atlas_emission
// divides) and the material texels of lobe points (voxelize_atlas_material divides).
layout(constant_id = 0) const bool HAS_EMISSION = false;
layout(constant_id = 1) const bool HAS_MATERIAL = false;

layout(location = 0) flat in vec3 g_albedo;
layout(location = 1) flat in vec4 g_normal;
layout(location = 2) flat in vec4 g_emission;
layout(location = 3) flat in vec4 g_material;
layout(location = 0) out vec4 o_albedo_weight;
layout(location = 1) out vec4 o_normal_sum;
layout(location = 2) out vec4 o_slot2;
layout(location = 3) out vec4 o_slot3;

void main() {
    o_albedo_weight = vec4(g_albedo, 1.0);
    o_normal_sum = g_normal;
    vec4 emission = g_emission.w > 0.0 ? vec4(g_emission.rgb, 1.0) : vec4(0.0);
    if (HAS_EMISSION) o_slot2 = emission;
    if (HAS_MATERIAL && !HAS_EMISSION) o_slot2 = g_material;
    if (HAS_MATERIAL && HAS_EMISSION) o_slot3 = g_material;
}

#version 450
// Resolves the atlas accumulation layers into the albedo and normal volumes that the path
// tracer samples: mean albedo (a = 1 where any point landed, 0 elsewhere, so the volume is
// congruent with the bits) and the normalized normal sum. Two sources add up: the static
// objects' sums (splatted once) and this frame's dynamic objects (Thiedemann 2010, §4.3.3 keeps a static
// copy the same way). Every voxel is written, so voxels that emptied are cleared.
// One depth slice per workgroup row: the sums are 2D array layers, so a group stays inside
// one layer of each.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler2DArray static_albedo;   // rgb sum, a = count
layout(set = 0, binding = 1) uniform sampler2DArray static_normal;   // xyz sum
layout(set = 0, binding = 2) uniform sampler2DArray frame_albedo;
layout(set = 0, binding = 3) uniform sampler2DArray frame_normal;
layout(set = 0, binding = 4, rgba8) uniform writeonly image3D albedo_volume;
layout(set = 0, binding = 5, rgba8_snorm) uniform writeonly image3D normal_volume;

layout(push_constant) uniform Push {
    uvec4 dims;   // res_x, res_y, D; w: bit 0 = static sums bound, bit 1 = frame sums bound
} pc;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(uvec3(v), pc.dims.xyz))) {
        return;
    }
    vec4 a = vec4(0.0);
    vec3 n = vec3(0.0);
    if ((pc.dims.w & 1u) != 0u) {
        a += texelFetch(static_albedo, v, 0);
        n += texelFetch(static_normal, v, 0).xyz;
    }
    if ((pc.dims.w & 2u) != 0u) {
        a += texelFetch(frame_albedo, v, 0);
        n += texelFetch(frame_normal, v, 0).xyz;
    }
    // Opposite faces inside one voxel (thin walls) cancel; a zero normal makes the path
    // tracer face the arriving ray, as it does for any unknown normal.
    float len = length(n);
    imageStore(albedo_volume, v, a.w > 0.0 ? vec4(a.rgb / a.w, 1.0) : vec4(0.0));
    imageStore(normal_volume, v, vec4(len > 1e-6 ? n / len : vec3(0.0), 0.0));
}

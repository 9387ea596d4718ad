#version 450
// Resolves the atlas material sums (voxelize_atlas_volumes.frag) into the material volume the
// path tracer reads (material_texel's encoding, material_lobe.glsl's voxel_lobe): where Phong
// or GGX points are at least half of a voxel's points (the normal sums' w over the albedo
// sums' count), the mean texel of those points; Lambert (0) elsewhere. A voxel where Phong
// and GGX points meet mixes their w (n + 1 and -1) and decodes as the majority's kind with
// its parameters diluted. Static sums + this frame's, as voxelize_atlas_resolve.comp; every
// voxel is written.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler2DArray static_albedo;    // a = point count
layout(set = 0, binding = 1) uniform sampler2DArray static_normal;    // w = lobe point count
layout(set = 0, binding = 2) uniform sampler2DArray static_material;  // texel sum
layout(set = 0, binding = 3) uniform sampler2DArray frame_albedo;
layout(set = 0, binding = 4) uniform sampler2DArray frame_normal;
layout(set = 0, binding = 5) uniform sampler2DArray frame_material;
layout(set = 0, binding = 6, rgba16f) uniform writeonly image3D material_volume;

layout(push_constant) uniform Push {
    uvec4 dims;   // res_x, res_y, D; w: bit 0 = static sums bound, bit 1 = frame sums bound
} pc;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(uvec3(v), pc.dims.xyz))) {
        return;
    }
    float count = 0.0, lobes = 0.0;
    vec4 sum = vec4(0.0);
    if ((pc.dims.w & 1u) != 0u) {
        count += texelFetch(static_albedo, v, 0).a;
        lobes += texelFetch(static_normal, v, 0).w;
        sum += texelFetch(static_material, v, 0);
    }
    if ((pc.dims.w & 2u) != 0u) {
        count += texelFetch(frame_albedo, v, 0).a;
        lobes += texelFetch(frame_normal, v, 0).w;
        sum += texelFetch(frame_material, v, 0);
    }
    bool lobe = lobes > 0.0 && 2.0 * lobes >= count;
    imageStore(material_volume, v, lobe ? sum / lobes : vec4(0.0));
}

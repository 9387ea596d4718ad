#version 450
// Builds, once per atlas, the list of valid texels (Thiedemann 2010, §4.3.1 step 2: a point list, not a
// draw of every texel with discards): appends every rendered texel to a buffer whose first
// word counts them, as (model-space position bits, triangle index): voxelize_atlas reads
// the position, voxelize_atlas_volumes also the triangle's normal and albedo. One dispatch
// per band of atlas rows, each into its own buffer with room for all the band's texels, so
// no buffer exceeds the storage-buffer range (gpu_atlas.rs, render_atlas_points_chunked).
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D atlas;
layout(set = 0, binding = 1, std430) buffer Points { uint count; uint pad[3]; uvec4 points[]; };

layout(push_constant) uniform Push {
    uint row0;   // first atlas row of the band
    uint rows;   // rows in the band
} pc;

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, int(pc.row0));
    if (gl_GlobalInvocationID.y >= pc.rows || any(greaterThanEqual(xy, textureSize(atlas, 0)))) {
        return;
    }
    vec4 p = texelFetch(atlas, xy, 0);
    if (p.w > 0.0) {
        uint i = atomicAdd(count, 1u);
        points[i] = uvec4(floatBitsToUint(p.xyz), uint(p.w) - 1u);
    }
}

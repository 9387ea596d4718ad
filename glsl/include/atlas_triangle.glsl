// One triangle of an automatic atlas (src/voxel/gpu_atlas.rs GpuAtlasTriangle, std430).
#ifndef ATLAS_TRIANGLE_GLSL
#define ATLAS_TRIANGLE_GLSL
struct AtlasTriangle {
    vec4 p[3];    // model-space vertices, w unused
    vec4 uv01;    // atlas texel coordinates of vertices 0 (xy) and 1 (zw)
    vec4 uv2;     // vertex 2 (xy), zw unused
    uvec4 cell;   // x, y, width, height in texels: the triangle owns texels only inside it
};
#endif

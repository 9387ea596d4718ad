#version 450
// Renders an automatic atlas (src/voxel/atlas.rs): each triangle's cell is drawn as a quad
// (6 vertices per triangle, no vertex buffer) with the atlas position as clip position
// (Thiedemann 2010, §4.2.2, `gl_Position = uv*2-1`); the fragment shader keeps the texels the triangle
// owns. Drawing the whole cell makes coverage conservative for thin and tiny triangles.
#include "atlas_triangle.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Triangles { AtlasTriangle tris[]; };
layout(push_constant) uniform Push { vec4 atlas_size; } pc;   // width, height (texels)

layout(location = 0) flat out uint v_tri;

void main() {
    uint tri = uint(gl_VertexIndex) / 6u;
    uint corner = uint(gl_VertexIndex) % 6u;
    const vec2 CORNERS[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(0, 1),
                                    vec2(1, 0), vec2(1, 1), vec2(0, 1));
    uvec4 cell = tris[tri].cell;
    vec2 texel = vec2(cell.xy) + CORNERS[corner] * vec2(cell.zw);
    gl_Position = vec4(texel / pc.atlas_size.xy * 2.0 - 1.0, 0.0, 1.0);
    v_tri = tri;
}

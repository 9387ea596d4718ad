#version 450
// Shadow maps: every shadow view (spot map, directional map, each cube face or paraboloid
// hemisphere of a point light) is one layer of a single depth array; the geometry shader routes
// triangles to their layer.

// Paraboloid views: paraboloid.glsl (a box around each triangle's curved image).
#include "frame.glsl"
#include "paraboloid.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(location = 0) in vec2 in_tex_uv[];

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    // The first layer of the attachment: a pass that draws one view into one layer of the
    // array (a cached shadow map) has gl_Layer = view - layer_base.
    uint layer_base;
} pc;

// Paraboloid only: uv of the fragment (exact, as w = 1), the triangle's vertices in the
// hemisphere frame (w 1; w 0 for the other projections), near and far.
layout(location = 0) out vec2 out_uv;
layout(location = 1) flat out vec4 out_v0;
layout(location = 2) flat out vec3 out_v1;
layout(location = 3) flat out vec3 out_v2;
layout(location = 4) flat out vec2 out_range;
// The other projections: world position, for dissolve coverage (shadow_depth.frag).
layout(location = 5) out vec3 out_world;
// Texture coordinates for alpha maps: interpolated (other projections), or those of vertex 2
// (paraboloid views; vertices 0 and 1 in out_t01, weighted by the hit's barycentric weights).
layout(location = 6) out vec2 out_tex_uv;
layout(location = 7) flat out vec4 out_t01;

void emit_corner(vec2 uv, GpuShadowView sv, vec3 tri[3]) {
    // Depth comes from the fragment shader (gl_FragDepth); the box's own is irrelevant.
    gl_Position = vec4(uv, 0.0, 1.0);
    gl_Layer = int(pc.view - pc.layer_base);
    out_uv = uv;
    out_v0 = vec4(tri[0], 1.0);
    out_v1 = tri[1];
    out_v2 = tri[2];
    out_range = sv.params.zw;
    out_world = vec3(0.0);
    out_tex_uv = in_tex_uv[2];
    out_t01 = vec4(in_tex_uv[0], in_tex_uv[1]);
    EmitVertex();
}

void main() {
    GpuShadowView sv = frame.shadow_views[pc.view];
    if (sv.params.y < 1.5) {
        for (int i = 0; i < 3; ++i) {
            gl_Position = sv.view_proj * gl_in[i].gl_Position;
            gl_Layer = int(pc.view - pc.layer_base);
            out_uv = vec2(0.0);
            out_v0 = vec4(0.0);
            out_v1 = vec3(0.0);
            out_v2 = vec3(0.0);
            out_range = sv.params.zw;
            out_world = gl_in[i].gl_Position.xyz;
            out_tex_uv = in_tex_uv[i];
            out_t01 = vec4(0.0);
            EmitVertex();
        }
        EndPrimitive();
        return;
    }
    vec3 d[3];
    for (int i = 0; i < 3; ++i) d[i] = (sv.view_proj * gl_in[i].gl_Position).xyz;
    vec2 lo, hi;
    if (!paraboloid_triangle_box(d, lo, hi)) return;
    emit_corner(vec2(lo.x, lo.y), sv, d);
    emit_corner(vec2(hi.x, lo.y), sv, d);
    emit_corner(vec2(lo.x, hi.y), sv, d);
    emit_corner(vec2(hi.x, hi.y), sv, d);
    EndPrimitive();
}

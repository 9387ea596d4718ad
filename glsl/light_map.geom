#version 450
// Reflective light maps: route each triangle to the layer of the light view being drawn
// (the same views as the shadow maps, at the light maps' own resolution). Paraboloid views
// (area-light elements) as shadow_depth draws them (paraboloid.glsl): a uv box around the
// triangle's curved image, whose texels light_map.frag keeps where their ray hits the
// triangle, with the hit's world position and normal from its barycentric weights.
#include "frame.glsl"
#include "paraboloid.glsl"

// Whether the area lights' views get light maps: only the hemisphere method reads them (the
// VPLs sample area lights in gi_vpl_emit), and they are the costly paraboloid kind.
layout(constant_id = 2) const bool AREA_LIGHT_MAPS = true;

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

layout(location = 0) in vec3 in_normal[];
layout(location = 1) in vec2 in_uv[];
layout(location = 0) out vec3 out_normal;
layout(location = 1) out vec3 out_world;
// Paraboloid views only (w of out_v0 is 1 there, 0 for the other projections): the map point,
// the triangle in the hemisphere frame, in the world, its vertex normals, near and far.
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out vec4 out_v0;
layout(location = 4) flat out vec3 out_v1;
layout(location = 5) flat out vec3 out_v2;
layout(location = 6) flat out vec3 out_w0;
layout(location = 7) flat out vec3 out_w1;
layout(location = 8) flat out vec3 out_w2;
layout(location = 9) flat out vec3 out_n0;
layout(location = 10) flat out vec3 out_n1;
layout(location = 11) flat out vec3 out_n2;
// Near and far (xy), and the texture coordinates of vertex 2 (zw).
layout(location = 12) flat out vec4 out_range_t2;
// The texture coordinates: interpolated (other projections), or those of vertices 0 and 1
// (paraboloid views, weighted by the hit's barycentric weights in light_map.frag).
layout(location = 13) out vec2 out_tex_uv;
layout(location = 14) flat out vec4 out_t01;

void emit_corner(vec2 uv, GpuShadowView sv, vec3 d[3]) {
    // Depth comes from the fragment shader (gl_FragDepth); the box's own is irrelevant.
    gl_Position = vec4(uv, 0.0, 1.0);
    gl_Layer = int(pc.view);
    out_normal = vec3(0.0);
    out_world = vec3(0.0);
    out_uv = uv;
    out_v0 = vec4(d[0], 1.0);
    out_v1 = d[1];
    out_v2 = d[2];
    out_w0 = gl_in[0].gl_Position.xyz;
    out_w1 = gl_in[1].gl_Position.xyz;
    out_w2 = gl_in[2].gl_Position.xyz;
    out_n0 = in_normal[0];
    out_n1 = in_normal[1];
    out_n2 = in_normal[2];
    out_range_t2 = vec4(sv.params.zw, in_uv[2]);
    out_tex_uv = vec2(0.0);
    out_t01 = vec4(in_uv[0], in_uv[1]);
    EmitVertex();
}

// Whether view v belongs to an area light: a sampled element, or a whole sphere under PCSS (a
// point light with a size in spot.w).
bool area_light_view(uint v) {
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight l = frame.lights[i];
        if (v >= l.info.y && v < l.info.y + l.info.z) {
            return l.info.x == LIGHT_ELEMENT || (l.info.x == LIGHT_POINT && l.spot.w > 0.0);
        }
    }
    return false;
}

void main() {
    GpuShadowView sv = frame.shadow_views[pc.view];
    if (!AREA_LIGHT_MAPS && sv.params.y > 1.5 && area_light_view(pc.view)) return;
    if (sv.params.y < 1.5) {
        for (int i = 0; i < 3; ++i) {
            gl_Position = sv.view_proj * gl_in[i].gl_Position;
            gl_Layer = int(pc.view);
            out_normal = in_normal[i];
            out_world = gl_in[i].gl_Position.xyz;
            out_uv = vec2(0.0);
            out_v0 = vec4(0.0);
            out_v1 = vec3(0.0);
            out_v2 = vec3(0.0);
            out_w0 = vec3(0.0);
            out_w1 = vec3(0.0);
            out_w2 = vec3(0.0);
            out_n0 = vec3(0.0);
            out_n1 = vec3(0.0);
            out_n2 = vec3(0.0);
            out_range_t2 = vec4(0.0);
            out_tex_uv = in_uv[i];
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

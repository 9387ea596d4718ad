#version 450
// Shadow maps: every shadow view (spot map, directional map, each cube face or paraboloid
// hemisphere of a point light) is one layer of a single depth array; the geometry shader routes
// triangles to their layer.
//
// Paraboloid views (Brabec et al. 2002; digest_001_004.md A.1): a vertex at d = p - light in the
// hemisphere frame lands at uv = d.xy / (|d| + d.z), depth (|d| - near) / (far - near). The map
// is not linear, so a triangle is rasterized between its mapped vertices: its edges are chords
// of the true curved images. For an edge of angular length a the chord deviates from the arc by
// at most about a^2 / 8 in uv (times the 1/(1+z) scale), so coverage is off by up to
// res * a^2 / 16 texels; the 0.4 m blocker cube of the tests, 0.8 m from the light, is off by
// under one texel at 1024^2. Depth does not suffer as much: the fragment shader writes the
// distance along the texel's ray to the triangle's plane, clamped to the triangle's range.
// Triangles crossing the rim are clipped to the hemisphere (z >= 0), whose boundary maps onto
// the unit circle.
#include "frame.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
} pc;

// Paraboloid only: uv of the fragment (exact, as w = 1), the triangle's vertices in the
// hemisphere frame (w 1; w 0 for the other projections), near and far.
layout(location = 0) out vec2 out_uv;
layout(location = 1) flat out vec4 out_v0;
layout(location = 2) flat out vec3 out_v1;
layout(location = 3) flat out vec3 out_v2;
layout(location = 4) flat out vec2 out_range;

void emit_paraboloid(vec3 d, GpuShadowView sv, vec3 tri[3]) {
    float len = length(d);
    vec2 uv = d.xy / max(len + d.z, 1e-30);
    gl_Position = vec4(uv, clamp((len - sv.params.z) / (sv.params.w - sv.params.z), 0.0, 1.0), 1.0);
    gl_Layer = int(pc.view);
    out_uv = uv;
    out_v0 = vec4(tri[0], 1.0);
    out_v1 = tri[1];
    out_v2 = tri[2];
    out_range = sv.params.zw;
    EmitVertex();
}

void main() {
    GpuShadowView sv = frame.shadow_views[pc.view];
    if (sv.params.y < 1.5) {
        for (int i = 0; i < 3; ++i) {
            gl_Position = sv.view_proj * gl_in[i].gl_Position;
            gl_Layer = int(pc.view);
            out_uv = vec2(0.0);
            out_v0 = vec4(0.0);
            out_v1 = vec3(0.0);
            out_v2 = vec3(0.0);
            out_range = sv.params.zw;
            EmitVertex();
        }
        EndPrimitive();
        return;
    }
    vec3 d[3];
    for (int i = 0; i < 3; ++i) d[i] = (sv.view_proj * gl_in[i].gl_Position).xyz;
    // Clip to z >= 0 (one plane: at most four vertices), emitted in strip order.
    vec3 poly[4];
    int count = 0;
    for (int i = 0; i < 3; ++i) {
        vec3 a = d[i], b = d[(i + 1) % 3];
        if (a.z >= 0.0) poly[count++] = a;
        if ((a.z >= 0.0) != (b.z >= 0.0)) poly[count++] = mix(a, b, a.z / (a.z - b.z));
    }
    if (count < 3) return;
    emit_paraboloid(poly[0], sv, d);
    emit_paraboloid(poly[1], sv, d);
    if (count == 4) {
        emit_paraboloid(poly[3], sv, d);
        emit_paraboloid(poly[2], sv, d);
    } else {
        emit_paraboloid(poly[2], sv, d);
    }
    EndPrimitive();
}

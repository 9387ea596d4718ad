#version 450
// Shadow maps: every shadow view (spot map, directional map, each cube face or paraboloid
// hemisphere of a point light) is one layer of a single depth array; the geometry shader routes
// triangles to their layer.
//
// Paraboloid views (Brabec et al. 2002): a direction d of the hemisphere
// frame lands at uv = d.xy / (|d| + d.z). The map is stereographic, so a straight edge (a great-
// circle arc seen from the light) maps to a circular arc, not to the chord between its mapped
// vertices. Rasterizing the mapped triangle would cover the wrong texels: up to 4 texels at
// 1024^2 along the red box's top edges in point_light.toml, where a side face's chord overshoots
// into the top's image and its plane, extended past the edge, is nearer than the top (the
// streak the depth clamp could not remove). Instead the geometry shader emits a box in uv that
// surely contains the triangle's curved image, and shadow_depth_paraboloid.frag keeps exactly
// the texels whose ray hits the triangle, at the exact distance. Triangles crossing the rim
// are clipped to the hemisphere (z >= 0), whose boundary maps onto the unit circle.
#include "frame.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
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

vec2 paraboloid_uv(vec3 d) {
    return d.xy / max(length(d) + d.z, 1e-30);
}

// Largest distance between the image of segment ab and its chord. The image is an arc of a
// circle (stereographic maps circles to circles), and inside the unit disk a minor arc: the
// image of a great circle's upper half meets the rim at antipodal points, so its chord through
// the origin leaves the circle's center on the far side. Three points of the arc give the
// circle's curvature k = 4 area / (|e0| |e1| |e2|) (circumradius), and a minor arc of chord c
// bulges by its sagitta s = R - sqrt(R^2 - c^2/4) = (c/2)^2 k / (1 + sqrt(1 - (c k / 2)^2)),
// written without the cancellation for nearly straight arcs.
float arc_sagitta(vec3 a, vec3 b) {
    vec2 pa = paraboloid_uv(a), pb = paraboloid_uv(b), pm = paraboloid_uv(0.5 * (a + b));
    vec2 e0 = pb - pa, e1 = pm - pa, e2 = pb - pm;
    float lens = length(e0) * length(e1) * length(e2);
    if (lens <= 0.0) return 0.0;
    float k = 2.0 * abs(e0.x * e1.y - e0.y * e1.x) / lens;
    float h = 0.5 * length(e0);
    return h * h * k / (1.0 + sqrt(max(1.0 - h * h * k * k, 0.0)));
}

void emit_corner(vec2 uv, GpuShadowView sv, vec3 tri[3]) {
    // Depth comes from the fragment shader (gl_FragDepth); the box's own is irrelevant.
    gl_Position = vec4(uv, 0.0, 1.0);
    gl_Layer = int(pc.view);
    out_uv = uv;
    out_v0 = vec4(tri[0], 1.0);
    out_v1 = tri[1];
    out_v2 = tri[2];
    out_range = sv.params.zw;
    out_world = vec3(0.0);
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
            out_world = gl_in[i].gl_Position.xyz;
            EmitVertex();
        }
        EndPrimitive();
        return;
    }
    vec3 d[3];
    for (int i = 0; i < 3; ++i) d[i] = (sv.view_proj * gl_in[i].gl_Position).xyz;
    // Clip to z >= 0 (one plane: at most four vertices); the clipped polygon's curved image is
    // bounded by its edges' arcs, each within its chord's box grown by its sagitta.
    vec3 poly[4];
    int count = 0;
    for (int i = 0; i < 3; ++i) {
        vec3 a = d[i], b = d[(i + 1) % 3];
        if (a.z >= 0.0) poly[count++] = a;
        if ((a.z >= 0.0) != (b.z >= 0.0)) poly[count++] = mix(a, b, a.z / (a.z - b.z));
    }
    if (count < 3) return;
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    float grow = 0.0;
    for (int i = 0; i < count; ++i) {
        vec2 uv = paraboloid_uv(poly[i]);
        lo = min(lo, uv);
        hi = max(hi, uv);
        grow = max(grow, arc_sagitta(poly[i], poly[(i + 1) % count]));
    }
    // A little slack for rounding (1/2000 of the map, half a texel at 1024^2): the fragment
    // shader's exact test decides coverage, the box only has to contain it.
    grow = grow * 1.01 + 1e-3;
    lo = max(lo - grow, vec2(-1.0));
    hi = min(hi + grow, vec2(1.0));
    if (any(greaterThanEqual(lo, hi))) return;
    emit_corner(vec2(lo.x, lo.y), sv, d);
    emit_corner(vec2(hi.x, lo.y), sv, d);
    emit_corner(vec2(lo.x, hi.y), sv, d);
    emit_corner(vec2(hi.x, hi.y), sv, d);
    EndPrimitive();
}

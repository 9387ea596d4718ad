#version 450
// Model-space position of the atlas texel's sample: the closest point of the triangle to the
// texel centre, kept when it is within √2/2 texel (the coverage rule of src/voxel/atlas.rs,
// whose `closest_point` this mirrors). w = triangle index + 1, exact in f32 below 2^24
// (render_atlas_points checks the count); unowned texels stay cleared (w = 0 = invalid).
#include "atlas_triangle.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Triangles { AtlasTriangle tris[]; };
layout(location = 0) flat in uint v_tri;
layout(location = 0) out vec4 o_position;

const float COVER_RADIUS = 0.70710678;

float perp(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// Barycentrics of the closest point of triangle (a, b, c) to q; degenerate triangles fall
// back to the closest point on an edge.
vec3 closest_on_triangle(vec2 a, vec2 b, vec2 c, vec2 q, out vec2 closest) {
    float area2 = perp(b - a, c - a);
    if (abs(area2) > 1e-12) {
        float l0 = perp(b - q, c - q) / area2;
        float l1 = perp(c - q, a - q) / area2;
        float l2 = 1.0 - l0 - l1;
        if (l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0) {
            closest = q;
            return vec3(l0, l1, l2);
        }
    }
    vec2 p[3] = vec2[3](a, b, c);
    float best_d = 1e30;
    vec3 best = vec3(1, 0, 0);
    closest = a;
    for (int e = 0; e < 3; ++e) {
        vec2 s0 = p[e];
        vec2 s1 = p[(e + 1) % 3];
        vec2 d = s1 - s0;
        float len2 = dot(d, d);
        float s = len2 > 0.0 ? clamp(dot(q - s0, d) / len2, 0.0, 1.0) : 0.0;
        vec2 x = s0 + d * s;
        float dist = dot(x - q, x - q);
        if (dist < best_d) {
            best_d = dist;
            vec3 bary = vec3(0.0);
            bary[e] = 1.0 - s;
            bary[(e + 1) % 3] = s;
            best = bary;
            closest = x;
        }
    }
    return best;
}

void main() {
    AtlasTriangle t = tris[v_tri];
    vec2 q = gl_FragCoord.xy;
    vec2 closest;
    vec3 bary = closest_on_triangle(t.uv01.xy, t.uv01.zw, t.uv2.xy, q, closest);
    if (distance(closest, q) > COVER_RADIUS) {
        discard;
    }
    o_position = vec4(bary.x * t.p[0].xyz + bary.y * t.p[1].xyz + bary.z * t.p[2].xyz,
                      float(v_tri + 1u));
}

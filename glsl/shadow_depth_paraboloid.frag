#version 450
// Shadow maps of a frame with paraboloid views (see shadow_depth.geom). The paraboloid map is
// not linear, so the rasterizer's interpolated depth is only exact at the vertices; instead the
// distance along the texel's ray to the triangle's plane is written, clamped to the distances
// the triangle has: where the rasterized chord overshoots the curved edge, the plane's extension
// could otherwise shadow whatever lies beyond that edge. Other views keep their rasterized
// depth. Paraboloid inverse (stereographic): d = (2x, 2y, 1 - x^2 - y^2) / (1 + x^2 + y^2).

layout(location = 0) in vec2 in_uv;
layout(location = 1) flat in vec4 in_v0;  // w 1: a paraboloid view
layout(location = 2) flat in vec3 in_v1;
layout(location = 3) flat in vec3 in_v2;
layout(location = 4) flat in vec2 in_range;  // near, far

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
vec3 closest_on_triangle(vec3 p, vec3 a, vec3 b, vec3 c) {
    vec3 ab = b - a, ac = c - a, ap = p - a;
    float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    vec3 bp = p - b;
    float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
    vec3 cp = p - c;
    float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    float denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

void main() {
    gl_FragDepth = gl_FragCoord.z;
    if (in_v0.w == 0.0) return;
    vec3 a = in_v0.xyz;
    vec3 n = cross(in_v1 - a, in_v2 - a);
    float r2 = dot(in_uv, in_uv);
    vec3 dir = vec3(2.0 * in_uv, 1.0 - r2) / (1.0 + r2);
    float cos_n = dot(n, dir);
    // Edge-on to the light: the interpolated depth is as good as any.
    if (abs(cos_n) <= 1e-6 * length(n)) return;
    float t = dot(n, a) / cos_n;
    if (t <= 0.0) return;
    // Distances on the triangle lie between its point nearest to the light and its farthest
    // vertex; moving the hit point onto the triangle instead would shift it sideways and
    // break the exact depth that coplanar neighbours (a quad's diagonal) rely on.
    float lo = length(closest_on_triangle(vec3(0.0), a, in_v1, in_v2));
    float hi = max(length(a), max(length(in_v1), length(in_v2)));
    float dist = clamp(t, lo, hi);
    gl_FragDepth = clamp((dist - in_range.x) / (in_range.y - in_range.x), 0.0, 1.0);
}

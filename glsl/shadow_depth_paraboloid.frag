#version 450
// Shadow maps of a frame with paraboloid views (see shadow_depth.geom, which covers a box
// around each triangle's curved image). A texel keeps a triangle exactly when the ray through
// its center hits the triangle, and stores the exact distance along that ray. Both interpolated
// depth (linear between the mapped vertices, while the map is not) and rasterized coverage
// (chords instead of arcs) are wrong inside large triangles (Brabec et al. 2002 and
// Dachsbacher 2014, "Echtzeit-Schattenverfahren Teil 3", ask to tessellate finely instead). Other
// views keep their rasterized depth. Paraboloid inverse (stereographic):
// d = (2x, 2y, 1 - x^2 - y^2) / (1 + x^2 + y^2).
// Materials with MTL d < 1 cover a fraction d of the texels (dissolve.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;

#include "dissolve.glsl"

struct GpuMaterial {
    vec4 albedo;  // a: opacity (gbuffer.frag has the whole layout)
    vec4 specular;
    uvec4 flags;
};
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
} pc;

layout(location = 0) in vec2 in_uv;
layout(location = 1) flat in vec4 in_v0;  // w 1: a paraboloid view
layout(location = 2) flat in vec3 in_v1;
layout(location = 3) flat in vec3 in_v2;
layout(location = 4) flat in vec2 in_range;  // near, far
layout(location = 5) in vec3 in_world;        // the other projections

void main() {
    float opacity = materials[pc.material].albedo.a;
    gl_FragDepth = gl_FragCoord.z;
    if (in_v0.w == 0.0) {
        if (HAS_DISSOLVE && opacity < dissolve_threshold(in_world)) discard;
        return;
    }
    float r2 = dot(in_uv, in_uv);
    vec3 dir = vec3(2.0 * in_uv, 1.0 - r2) / (1.0 + r2);
    vec3 a = in_v0.xyz, b = in_v1, c = in_v2;
    vec3 ab = cross(a, b), bc = cross(b, c), ca = cross(c, a);
    // Ray-plane distance: n . (t dir) = n . a with n = (b - a) x (c - a), whose n . a is
    // det(a, b, c).
    float orient = dot(a, bc);
    vec3 n = cross(b - a, c - a);
    float cos_n = dot(n, dir);
    float dist = orient / cos_n;
    // Dissolve takes derivatives of the hit point: before any discard (the hemisphere frame is
    // rigid, as good as world space for a pattern that sticks to the surface).
    float coverage_threshold = HAS_DISSOLVE ? dissolve_threshold(dir * dist) : 0.0;
    // Past the rim is the other hemisphere's, and no lookup reads it (shadow.glsl).
    if (r2 > 1.0) discard;
    // Edge-on to the light: the triangle covers no solid angle; its neighbours cover the rest.
    if (orient == 0.0) discard;
    // The ray from the light (the origin) hits the triangle iff it lies on the inner side of
    // the three planes through the light and an edge (the triangle's cone), on the side that
    // the triangle's own orientation det(a, b, c) calls inner. The neighbour across an edge
    // evaluates the same cross product negated, so shared edges leave no gap; the tolerance
    // (relative, 1e-6) lets both keep a texel that rounding puts exactly on the edge.
    float s = sign(orient);
    if (s * dot(dir, ab) < -1e-6 * length(ab) || s * dot(dir, bc) < -1e-6 * length(bc) ||
        s * dot(dir, ca) < -1e-6 * length(ca)) {
        discard;
    }
    if (s * cos_n <= 0.0) discard;
    if (HAS_DISSOLVE && opacity < coverage_threshold) discard;
    gl_FragDepth = clamp((dist - in_range.x) / (in_range.y - in_range.x), 0.0, 1.0);
}

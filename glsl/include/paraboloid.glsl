// Dual-paraboloid views (Brabec et al. 2002), as shadow_depth and light_map draw them. A
// direction d of the hemisphere frame (the view's rigid view_proj) lands at
// uv = d.xy / (|d| + d.z). The map is stereographic, so a straight edge (a great-circle arc
// seen from the light) maps to a circular arc, not to the chord between its mapped vertices:
// rasterizing the mapped triangle would cover the wrong texels (up to 4 texels at 1024^2 along
// the red box's top edges in point_light.toml, where a side face's chord overshoots into the
// top's image). Instead the geometry shader emits a box in uv that surely contains the
// triangle's curved image (paraboloid_triangle_box), and the fragment shader keeps exactly the
// texels whose ray hits the triangle, at the exact distance (paraboloid_ray). Triangles
// crossing the rim are clipped to the hemisphere (z >= 0), whose boundary maps onto the unit
// circle. Inverse (stereographic): d = (2x, 2y, 1 - x^2 - y^2) / (1 + x^2 + y^2).
#ifndef PARABOLOID_GLSL
#define PARABOLOID_GLSL

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

// The uv box [lo, hi] that surely holds the image of triangle d (hemisphere frame) clipped to
// z >= 0; false when nothing of it is left. The clipped polygon's curved image is bounded by
// its edges' arcs, each within its chord's box grown by its sagitta.
bool paraboloid_triangle_box(vec3 d[3], out vec2 lo, out vec2 hi) {
    vec3 poly[4];
    int count = 0;
    for (int i = 0; i < 3; ++i) {
        vec3 a = d[i], b = d[(i + 1) % 3];
        if (a.z >= 0.0) poly[count++] = a;
        if ((a.z >= 0.0) != (b.z >= 0.0)) poly[count++] = mix(a, b, a.z / (a.z - b.z));
    }
    lo = vec2(1e30);
    hi = vec2(-1e30);
    if (count < 3) return false;
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
    return all(lessThan(lo, hi));
}

// The ray from the light (the origin of the hemisphere frame) through map point uv against the
// triangle (a, b, c) of that frame: its direction, the distance along it to the triangle's
// plane, the hit's barycentric weights of a, b, c, and whether it hits the triangle. The ray
// hits iff it lies on the inner side of the three planes through the light and an edge (the
// triangle's cone), on the side the triangle's orientation det(a, b, c) calls inner. The
// neighbour across an edge evaluates the same cross product negated, so shared edges leave no
// gap; the tolerance (relative, 1e-6) lets both keep a texel that rounding puts exactly on the
// edge. Past the rim (|uv| > 1) is the other hemisphere's and never a hit; so is a triangle
// edge-on to the light (it covers no solid angle; its neighbours cover the rest).
bool paraboloid_ray(vec2 uv, vec3 a, vec3 b, vec3 c, out vec3 dir, out float dist,
                    out vec3 bary) {
    float r2 = dot(uv, uv);
    dir = vec3(2.0 * uv, 1.0 - r2) / (1.0 + r2);
    vec3 ab = cross(a, b), bc = cross(b, c), ca = cross(c, a);
    // Ray-plane distance: n . (t dir) = n . a with n = (b - a) x (c - a), whose n . a is
    // det(a, b, c).
    float orient = dot(a, bc);
    vec3 n = cross(b - a, c - a);
    float cos_n = dot(n, dir);
    dist = orient / cos_n;
    // det(t dir, b, c) / det(a, b, c) and its cyclic siblings.
    bary = dist * vec3(dot(dir, bc), dot(dir, ca), dot(dir, ab)) / orient;
    float s = sign(orient);
    return r2 <= 1.0 && orient != 0.0 && s * dot(dir, ab) >= -1e-6 * length(ab) &&
           s * dot(dir, bc) >= -1e-6 * length(bc) && s * dot(dir, ca) >= -1e-6 * length(ca) &&
           s * cos_n > 0.0;
}

#endif

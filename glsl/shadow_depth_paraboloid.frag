#version 450
// Shadow maps of a frame with paraboloid views (see shadow_depth.geom). The paraboloid map is
// not linear, so the rasterizer's interpolated depth is only exact at the vertices; instead the
// distance to the triangle's plane along the texel's ray is written. Other views keep their
// rasterized depth. Paraboloid inverse (stereographic): d = (2x, 2y, 1 - x^2 - y^2) / (1 + x^2 + y^2).

layout(location = 0) in vec2 in_uv;
layout(location = 1) flat in vec4 in_plane;
layout(location = 2) flat in vec2 in_range;  // near, far

void main() {
    gl_FragDepth = gl_FragCoord.z;
    if (dot(in_plane.xyz, in_plane.xyz) == 0.0) return;
    float r2 = dot(in_uv, in_uv);
    vec3 dir = vec3(2.0 * in_uv, 1.0 - r2) / (1.0 + r2);
    float cos_n = dot(in_plane.xyz, dir);
    // Nearly edge-on to the light: the interpolated depth is as good as any.
    if (abs(cos_n) < 1e-4) return;
    float t = -in_plane.w / cos_n;
    // No point of the plane is closer than its distance to the light.
    if (t < abs(in_plane.w)) return;
    gl_FragDepth = clamp((t - in_range.x) / (in_range.y - in_range.x), 0.0, 1.0);
}

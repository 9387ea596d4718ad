// The environment light (the scene's `[environment]` table, src/scene/environment.rs): the
// radiance arriving from infinitely far away along a direction. Read by camera rays that miss
// every surface (deferred_direct.comp) and by GI rays that leave the voxel grid.
//
// The includer declares, before including this file:
//   layout(constant_id = 8) const uint ENVIRONMENT = 0u;  // ENVIRONMENT_NONE/CONSTANT/MAP
//   layout(set = 0, binding = N) uniform sampler2D environment_map;  // any image unless MAP
// and the frame constants `frame` (frame.glsl's GpuFrame: `environment` holds the constant's
// radiance or the map's scale in rgb, and the map's rotation about +Y in radians in w).
//
// Convention (Mitsuba 3's `envmap`, src/emitters/envmap.cpp): +Y is up; a world direction d is
// turned by -rotation about +Y into the map's frame, where u = atan2(x, -z) / 2pi (u = 0 along
// -Z, 1/4 along +X, 1/2 along +Z) and v = acos(y) / pi (the top row straight up). The CPU twin
// is `scene::environment::equirect_uv`.
#ifndef ENVIRONMENT_GLSL
#define ENVIRONMENT_GLSL

#define ENVIRONMENT_NONE 0u
#define ENVIRONMENT_CONSTANT 1u
#define ENVIRONMENT_MAP 2u

const float ENVIRONMENT_PI = 3.14159265358979323846;

// The map coordinates of unit world direction d under a map turned by `rotation` radians about
// +Y (counter-clockwise seen from above, as Mitsuba's `<rotate y="1"/>`).
vec2 environment_uv(vec3 d, float rotation) {
    float s = sin(rotation);
    float c = cos(rotation);
    vec3 l = vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    // atan(0, 0) is undefined in GLSL: straight up or down any u will do.
    float u = abs(l.x) + abs(l.z) > 0.0 ? atan(l.x, -l.z) / (2.0 * ENVIRONMENT_PI) : 0.0;
    float v = acos(clamp(l.y, -1.0, 1.0)) / ENVIRONMENT_PI;
    return vec2(fract(u), v);
}

// The world direction of map coordinates uv under the same rotation: the inverse of
// environment_uv (the CPU twin is `scene::environment::equirect_direction`).
vec3 environment_direction(vec2 uv, float rotation) {
    float phi = 2.0 * ENVIRONMENT_PI * uv.x;
    float theta = ENVIRONMENT_PI * uv.y;
    vec3 l = vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
    float s = sin(rotation);
    float c = cos(rotation);
    return vec3(c * l.x + s * l.z, l.y, -s * l.x + c * l.z);
}

// Radiance (W/(m^2 sr)) arriving along -d, i.e. seen by a ray travelling along unit d.
vec3 environment_radiance(vec3 d) {
    if (ENVIRONMENT == ENVIRONMENT_NONE) return vec3(0.0);
    if (ENVIRONMENT == ENVIRONMENT_CONSTANT) return frame.environment.rgb;
    vec2 uv = environment_uv(d, frame.environment.w);
    // Bilinear, repeating in u (the sampler) but not across the poles: v stays within the
    // first and last rows' centers.
    float h = float(textureSize(environment_map, 0).y);
    uv.y = clamp(uv.y, 0.5 / h, 1.0 - 0.5 / h);
    return textureLod(environment_map, uv, 0.0).rgb * frame.environment.rgb;
}

// Where a voxel-space ray o + t dv leaves the grid [0, dims) (t in the ray's own parameter):
// the nearest exit plane. An origin outside the grid gives t <= 0.
float environment_grid_exit_t(ivec3 dims, vec3 o, vec3 dv) {
    float t = 3.4e38;
    for (int i = 0; i < 3; ++i) {
        if (dv[i] == 0.0) continue;
        float plane = dv[i] > 0.0 ? float(dims[i]) : 0.0;
        t = min(t, (plane - o[i]) / dv[i]);
    }
    return t;
}

// What a GI ray that hit no voxel brings back (d its unit world direction, o and dv its
// voxel-space origin and direction, t_max its length in the same parameter): the environment
// if the ray left the grid within its length, since nothing outside the grid can block it.
// A ray that ran out of traversal steps, or whose length ended inside the grid, does not know
// what lies beyond and brings back nothing, as before there was an environment.
vec3 environment_after_miss(ivec3 dims, vec3 o, vec3 dv, float t_max, bool ran_out, vec3 d) {
    if (ENVIRONMENT == ENVIRONMENT_NONE || ran_out) return vec3(0.0);
    if (environment_grid_exit_t(dims, o, dv) > t_max) return vec3(0.0);
    return environment_radiance(d);
}

#endif

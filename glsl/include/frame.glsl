// Frame constants shared by the camera, shadow and shading passes.
// Mirrors `GpuFrame` in src/render/gpu.rs (a test checks the Rust layout).
#ifndef FRAME_GLSL
#define FRAME_GLSL

#define MAX_LIGHTS 64
#define MAX_SHADOW_VIEWS 64

#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u
#define LIGHT_ELEMENT 3u    // a sample of an area light: I(theta) = intensity max(cos theta, 0)

struct GpuLight {
    vec4 position;      // xyz world position (point, spot)
    vec4 direction;     // xyz unit direction light travels (spot, directional; element: normal)
    vec4 intensity;     // rgb: W/sr (point, spot) or W/m^2 (directional)
    vec4 spot;          // x cos(cutoff), y cutoff rad, z beam rad; w PCSS light size, m (element)
    uvec4 info;         // x kind, y first shadow view, z shadow view count (0: no shadow)
};

struct GpuShadowView {
    mat4 view_proj;     // world -> Vulkan clip of the shadow map layer (paraboloid: world ->
                        // hemisphere frame, light at the origin, +z the axis)
    vec4 params;        // x texel footprint per meter of distance (perspective), meters (ortho)
                        // or radians at the axis (paraboloid), y 0 perspective, 1 orthographic,
                        // 2 paraboloid, z near, w far
    vec4 axis;          // xyz the view's axis (cube face, hemisphere, spot/sun direction), w unused
};

struct GpuFrame {
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 camera_position;
    uvec4 counts;       // x lights, y shadow views, z width, w height
    vec4 shadow;        // x constant bias (depth units), y slope bias, z normal offset (texels), w PCF radius (texels)
    GpuLight lights[MAX_LIGHTS];
    GpuShadowView shadow_views[MAX_SHADOW_VIEWS];
    mat4 prev_view_proj;  // the previous frame's un-jittered view_proj (motion vectors)
    vec4 jitter_ndc;      // xy: this frame's TAA jitter in NDC, included in view_proj
    vec4 camera_forward;  // xyz unit viewing direction, w orthographic view height m (0: perspective)
    vec4 environment;     // rgb constant radiance or map scale, w map rotation about +Y (rad);
                          // environment.glsl reads it
    vec4 radiance_scale;  // the scene's pre-exposure (src/scene/pre_exposure.rs): half-float
                          // images hold radiance * x (x = 2^-k), their readers multiply by
                          // y = 2^k; both 1 for almost every scene
};

// World position of pixel `px` of a `size` frame at depth-buffer value `depth`: the pixel's
// center unprojected by `inv_view_proj`, the inverse of the camera-relative view-projection
// (GpuFrame's, the camera moved to the origin), plus the camera's position `camera_m`. Far from
// the world origin the unprojection then works with small numbers and only the final sum
// rounds, at ulp(|camera|); the full inverse lost about |camera| times the projection's
// condition number (1 km from the origin: shadow tests on points centimeters off).
vec3 pixel_world_position(mat4 inv_view_proj, vec3 camera_m, ivec2 px, vec2 size, float depth) {
    vec2 uv = (vec2(px) + 0.5) / size;
    vec4 wp = inv_view_proj * vec4(uv * 2.0 - 1.0, depth, 1.0);
    return camera_m + wp.xyz / wp.w;
}

// The camera's projection: `camera_forward` is GpuFrame's (xyz the unit viewing direction, w
// the orthographic view's height in meters, 0 under perspective projection). Under
// orthographic projection every view ray runs along the viewing direction, so the direction
// toward the camera is the same for every point, and the depth along the view (not the
// distance to the camera's position) orders points on one pixel's ray.
bool frame_orthographic(vec4 camera_forward) {
    return camera_forward.w > 0.0;
}

// Unit direction from `p` toward the camera (the view vector of shading): toward the camera's
// position under perspective projection, −forward under orthographic projection.
vec3 toward_camera(vec4 camera_position, vec4 camera_forward, vec3 p) {
    if (frame_orthographic(camera_forward)) return -camera_forward.xyz;
    return normalize(camera_position.xyz - p);
}

// How far `p` lies from the camera along its pixel's ray: the distance to the camera's
// position under perspective projection, the view depth (from the camera's plane) under
// orthographic projection.
float camera_distance(vec4 camera_position, vec4 camera_forward, vec3 p) {
    if (frame_orthographic(camera_forward)) return dot(p - camera_position.xyz, camera_forward.xyz);
    return distance(p, camera_position.xyz);
}

// View depth of `p` (meters along the viewing direction from the camera): clip w under
// perspective projection; under orthographic projection w is 1, so the depth is measured.
float view_depth(mat4 view_proj, vec4 camera_position, vec4 camera_forward, vec3 p) {
    if (frame_orthographic(camera_forward)) return dot(p - camera_position.xyz, camera_forward.xyz);
    return (view_proj * vec4(p, 1.0)).w;
}

// The length that scales screen-space filters' tolerances with a pixel's footprint: the
// distance to the camera under perspective projection (a pixel covers distance × 2 tan(fov/2)
// / height meters); under orthographic projection, where every pixel covers the same
// height / H meters, the view's height: the distance at which a perspective camera with
// 2 tan(fov_y/2) = 1 (53°) has that footprint. It does not change when the camera's plane
// moves along the view, which (near clipping aside) leaves an orthographic image unchanged.
float footprint_distance(vec4 camera_position, vec4 camera_forward, vec3 p) {
    if (frame_orthographic(camera_forward)) return camera_forward.w;
    return distance(p, camera_position.xyz);
}

// Mitsuba 3 `spot` falloff: 1 inside the beam, linear in angle to 0 at the cutoff.
// `cos_axis`: cosine between the spot axis and the direction from the light to the point.
float spot_falloff(GpuLight l, float cos_axis) {
    if (cos_axis <= l.spot.x) return 0.0;
    float theta = acos(clamp(cos_axis, -1.0, 1.0));
    if (theta <= l.spot.z) return 1.0;
    return clamp((l.spot.y - theta) / max(l.spot.y - l.spot.z, 1e-6), 0.0, 1.0);
}

// Angular factor of a point-like light toward a point at cosine `cos_axis` from its axis:
// Mitsuba's spot falloff, an area-light element's cosine (I = L A cos theta, one-sided), 1 for
// a point light.
float light_falloff(GpuLight l, float cos_axis) {
    if (l.info.x == LIGHT_SPOT) return spot_falloff(l, cos_axis);
    if (l.info.x == LIGHT_ELEMENT) return max(cos_axis, 0.0);
    return 1.0;
}

#endif

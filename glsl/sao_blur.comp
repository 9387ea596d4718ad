#version 450
// The depth-aware separable blur of the half-resolution SAO term (Oetke 2017 §2.5): a 7-tap
// Gaussian per direction at offsets 0, ±1, ±2, ±3 half-res texels, each tap weighted by
// exp(−Δz²/(2σ_z²)), σ_z = σ_rel·z_centre (depth difference relative to the centre's view
// distance). Run horizontally, then vertically. Texel (x, y) belongs to full-res pixel (2x, 2y).
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D gb_depth;
layout(set = 0, binding = 2) uniform sampler2D src;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D dst;

layout(push_constant) uniform Push {
    ivec2 direction;
    float depth_sigma_rel;
} pc;

vec3 world_at(ivec2 px, vec2 size) {
    float depth = texelFetch(gb_depth, px, 0).r;
    return pixel_world_position(frame.inv_view_proj, frame.camera_position.xyz, px, size, depth);
}

// Linear view distance from the depth buffer (distance to the camera, meters; the view depth
// under orthographic projection).
float distance_at(ivec2 px, vec2 size) {
    return camera_distance(frame.camera_position, frame.camera_forward, world_at(px, size));
}

// Gaussian weights exp(−k²/(2·1.5²)) of offsets 0..3, normalized over ±3 (the thesis's 7
// linear-filtered fetches cover about the same support at full resolution).
const float WEIGHTS[4] = float[4](0.2707, 0.2167, 0.1113, 0.0366);

void main() {
    ivec2 hp = ivec2(gl_GlobalInvocationID.xy);
    ivec2 hsize = imageSize(dst);
    if (any(greaterThanEqual(hp, hsize))) return;
    ivec2 size = ivec2(frame.counts.zw);
    ivec2 c = min(hp * 2, size - 1);
    float centre = texelFetch(src, hp, 0).r;
    if (texelFetch(gb_depth, c, 0).r >= 1.0) {
        imageStore(dst, hp, vec4(centre));
        return;
    }
    vec3 p0 = world_at(c, vec2(size));
    float z0 = camera_distance(frame.camera_position, frame.camera_forward, p0);
    // σ_z scales with the pixel's footprint (footprint_distance: z0 under perspective).
    float sigma = max(pc.depth_sigma_rel * footprint_distance(frame.camera_position, frame.camera_forward, p0), 1e-6);
    float sum = 0.0;
    float wsum = 0.0;
    for (int k = -3; k <= 3; ++k) {
        ivec2 q = hp + pc.direction * k;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, hsize))) continue;
        ivec2 qf = min(q * 2, size - 1);
        if (texelFetch(gb_depth, qf, 0).r >= 1.0) continue;
        float dz = distance_at(qf, vec2(size)) - z0;
        float w = WEIGHTS[abs(k)] * exp(-dz * dz / (2.0 * sigma * sigma));
        sum += w * texelFetch(src, q, 0).r;
        wsum += w;
    }
    imageStore(dst, hp, vec4(wsum > 0.0 ? sum / wsum : centre));
}

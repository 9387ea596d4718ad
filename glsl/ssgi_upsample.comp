#version 450
// The screen-space GI's last step (Oetke 2017 §5.2, §5.5): the irradiance of the GI
// resolution joint-bilaterally upsampled to the frame against the full-resolution G-buffer
// geometry (level 0 of the pyramid). Writes the indirect image gi_filter and gi_composite
// read (irradiance; at Phong pixels the diffuse radiance ρ_d/π·E, which the composite adds as
// stored), the history the next frame's feedback reprojects (irradiance and the pixel's clip
// w), and this frame's camera as the next frame's previous camera.
#include "frame.glsl"
#include "ssgi.glsl"

layout(constant_id = 0) const bool HAS_PHONG = false;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1) uniform sampler2D coarse_value;
layout(set = 0, binding = 2) uniform sampler2D coarse_pos;
layout(set = 0, binding = 3) uniform sampler2D coarse_nrm;
layout(set = 0, binding = 4) uniform sampler2D fine_pos;
layout(set = 0, binding = 5) uniform sampler2D fine_nrm;
layout(set = 0, binding = 6) uniform sampler2D gb_albedo;
layout(set = 0, binding = 7) uniform sampler2D gb_specular;   // albedo when !HAS_PHONG
layout(set = 0, binding = 8, rgba32f) uniform writeonly image2D out_indirect;
layout(set = 0, binding = 9, rgba32f) uniform writeonly image2D history;
layout(set = 0, binding = 10, std430) writeonly buffer PrevCamera { mat4 prev_view_proj; };
#include "gbuffer_lobe.glsl"

layout(push_constant) uniform Push {
    float scale;   // frame pixels per GI texel
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(out_indirect);
    if (p == ivec2(0)) prev_view_proj = frame.view_proj;
    if (any(greaterThanEqual(p, size))) return;
    vec4 pz = texelFetch(fine_pos, p, 0);
    if (pz.w <= 0.0) {
        imageStore(out_indirect, p, vec4(0.0));
        imageStore(history, p, vec4(0.0));
        return;
    }
    vec3 n = texelFetch(fine_nrm, p, 0).xyz;
    vec3 e = ssgi_joint_bilateral(coarse_value, coarse_pos, coarse_nrm, p, pc.scale, n, pz.w);
    vec4 clip = frame.view_proj * vec4(pz.xyz, 1.0);
    imageStore(history, p, vec4(e, clip.w));
    bool phong = HAS_PHONG && any(greaterThan(gbuffer_phong_specular(gb_specular, p), vec3(0.0)));
    vec3 out_value = phong ? texelFetch(gb_albedo, p, 0).rgb / SSGI_PI * e : e;
    imageStore(out_indirect, p, vec4(out_value, 1.0));
}

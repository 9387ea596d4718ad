#version 450
// G-buffer pass: albedo (linear, 16-bit float so dark albedos keep 1% accuracy), world normal
// and shininess, and, only when the scene has Phong materials, the specular color.
layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_TEXTURES = false;

struct GpuMaterial {
    vec4 albedo;    // rgb albedo, a opacity
    vec4 specular;  // rgb specular reflectance, a shininess
    uvec4 flags;    // x: an albedo texture replaces albedo
};

#include "frame.glsl"
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// The draw's albedo texture (a 1x1 placeholder when the material has none).
layout(set = 0, binding = 2) uniform sampler2D albedo_texture;

layout(push_constant) uniform Push {
    mat4 model;
    uint material;
} pc;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec3 in_world;

layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_specular;

void main() {
    GpuMaterial m = materials[pc.material];
    vec3 n = normalize(in_normal);
    // Two-sided surfaces: shade the side the camera sees. Decided geometrically, not by
    // gl_FrontFacing, because the y-flipped projection inverts the winding.
    if (dot(n, frame.camera_position.xyz - in_world) < 0.0) n = -n;
    vec3 albedo = m.albedo.rgb;
    // OBJ texture coordinates have v up; image rows start at the top.
    if (HAS_TEXTURES && m.flags.x != 0u) albedo = texture(albedo_texture, vec2(in_uv.x, 1.0 - in_uv.y)).rgb;
    out_albedo = vec4(albedo, 1.0);
    out_normal = vec4(n, m.specular.a);
    if (HAS_PHONG) out_specular = vec4(m.specular.rgb, 1.0);
}

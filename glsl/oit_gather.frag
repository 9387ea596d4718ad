#version 450
// Transparent layers into per-pixel linked lists (Yang et al. 2010, "Real-time concurrent
// linked list construction on the GPU"; Dachsbacher 2014, part 3, order-independent
// transparency): every fragment of a material with MTL d < 1 that lies in front of the opaque
// depth (tested, not written) is shaded with the deferred pass's direct light
// (direct_light.glsl) plus its emission, then appended to a node buffer through an atomic
// counter, its node pointing at the pixel's previous head (an r32ui image, ~0u = end). A
// fragment past the buffer's capacity is dropped; the counter still counts it, so the host
// reads how many were lost. oit_resolve.comp sorts and blends the lists.
// Shaded from the constant material values and the albedo map (no bump or PBR maps).
layout(early_fragment_tests) in;  // a fragment behind the opaque depth appends nothing

layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 2) const bool HAS_TEXTURES = false;
// Some material has an alpha map (alpha_map.glsl): per-texel opacity (blend), or a cutout.
layout(constant_id = 3) const bool HAS_ALPHA_MAP = false;

struct GpuMaterial {
    vec4 albedo;    // rgb albedo, a opacity
    vec4 specular;  // rgb specular reflectance, a shininess
    uvec4 flags;    // x: an albedo texture replaces albedo (gbuffer.frag)
};
struct GpuMaterialPbr {
    vec4 ggx;       // x roughness, y metallic, z 1 for a GGX material
    vec4 emission;  // rgb W/(m^2 sr)
    uvec4 maps;     // 1 where the draw's map is used: x roughness, y metallic, z emission
};

#include "frame.glsl"
#include "brdf.glsl"
#include "alpha_map.glsl"
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#include "shadow.glsl"
#include "direct_light.glsl"
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// The draw's albedo texture (a 1x1 placeholder when the material has none).
layout(set = 0, binding = 2) uniform sampler2D albedo_texture;
layout(set = 0, binding = 3, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };
layout(set = 0, binding = 4) uniform sampler2DArray shadow_maps;
// Head of each pixel's list: the index of its nearest-appended node, ~0u for none.
layout(set = 0, binding = 5, r32ui) uniform coherent uimage2D heads;
// Node: x packHalf2x16(r, g), y packHalf2x16(b, alpha), z depth (float bits), w next.
layout(set = 0, binding = 6, std430) writeonly buffer Nodes { uvec4 nodes[]; };
// x: nodes requested this frame (may exceed y), y: capacity; z, w: oit_resolve's counts.
layout(set = 0, binding = 7, std430) coherent buffer Counters { uvec4 counters; };

layout(push_constant) uniform Push {
    mat4 model;
    uint material;
    // Rows of prev_model · model⁻¹ (the draw's world motion since the previous frame; a
    // row vector times it gives the point's previous world position): gbuffer.frag's motion
    // vectors only.
    mat3x4 motion;
} pc;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec3 in_world;

void main() {
    GpuMaterial m = materials[pc.material];
    GpuMaterialPbr mp = pbr[pc.material];
    vec3 n = normalize(in_normal);
    // Two-sided, as in gbuffer.frag: shade the side the camera sees.
    bool front = dot(n, toward_camera(frame.camera_position, frame.camera_forward, in_world)) >= 0.0;
    if (!front) n = -n;
    vec3 albedo = m.albedo.rgb;
    vec4 texel = HAS_TEXTURES ? texture(albedo_texture, vec2(in_uv.x, 1.0 - in_uv.y)) : vec4(1.0);
    if (HAS_TEXTURES && m.flags.x != 0u) albedo = texel.rgb;
    float opacity = HAS_ALPHA_MAP ? alpha_map_opacity(m.flags.w, m.albedo.a, texel.a) : m.albedo.a;
    // Cut away (or fully clear): no layer.
    if (HAS_ALPHA_MAP && opacity <= 0.0) return;
    vec4 lobe = vec4(m.specular.rgb, 1.0);
    float lobe_parameter = m.specular.a;
    if (HAS_GGX && mp.ggx.z != 0.0) {
        lobe = vec4(mix(vec3(0.04), albedo, mp.ggx.y), 2.0);
        lobe_parameter = mp.ggx.x;
        albedo *= 1.0 - mp.ggx.y;
    }
    vec3 wo = toward_camera(frame.camera_position, frame.camera_forward, in_world);
    vec3 lo = direct_radiance(shadow_maps, in_world, n, wo, albedo, lobe, lobe_parameter);
    // Emission leaves the front side only, as Mitsuba's area emitter.
    if (front) lo += mp.emission.rgb;
    // The node holds half floats: pre-exposed radiance (frame.glsl; oit_resolve scales back).
    lo *= frame.radiance_scale.x;

    uint index = atomicAdd(counters.x, 1u);
    if (index >= counters.y) return;  // full: dropped, and counted by counters.x
    uint next = imageAtomicExchange(heads, ivec2(gl_FragCoord.xy), index);
    nodes[index] = uvec4(packHalf2x16(lo.rg), packHalf2x16(vec2(lo.b, opacity)),
                         floatBitsToUint(gl_FragCoord.z), next);
}

// G-buffer pass: albedo (linear, 16-bit float so dark albedos keep 1% accuracy), world normal
// and lobe parameter, and, only when the scene has them, the specular lobe and the emission.
// Specular lobe (Phong or GGX materials): rgb Phong rho_s or GGX F0 = mix(0.04, base, metallic),
// a the lobe kind (1 Phong, 2 GGX); normal.w is the Phong exponent or the GGX roughness, and a
// GGX pixel's albedo is its diffuse color (1 - metallic) base (brdf.glsl, brdf_ggx).
// Color locations: 2 holds the specular lobe, or the emission when the scene has no lobe;
// 3 the emission when both exist; the motion vectors (scenes with moving objects under TAA)
// the next one after those (attachments exist only for what the scene has).
layout(constant_id = 0) const bool HAS_PHONG = false;
layout(constant_id = 1) const bool HAS_TEXTURES = false;
layout(constant_id = 2) const bool HAS_BUMP = false;
// Some material has MTL d < 1 (dissolve.glsl); otherwise no fragment is ever discarded.
layout(constant_id = 3) const bool HAS_DISSOLVE = false;
layout(constant_id = 4) const bool HAS_GGX = false;
layout(constant_id = 5) const bool HAS_EMISSION = false;
// Some material has an MTL PBR map (map_Pr, map_Pm, map_Ke).
layout(constant_id = 6) const bool HAS_PBR_MAPS = false;
// Moving objects under TAA: write the motion vector.
layout(constant_id = 7) const bool HAS_MOTION = false;
// Some material has per-texel alpha (alpha_map.glsl): a cutout or blend map in the alpha
// channel of binding 2.
layout(constant_id = 9) const bool HAS_ALPHA_MAP = false;
const bool HAS_LOBE = HAS_PHONG || HAS_GGX;

struct GpuMaterial {
    vec4 albedo;    // rgb albedo, a opacity
    vec4 specular;  // rgb specular reflectance, a shininess
    uvec4 flags;    // x: an albedo texture replaces albedo; y: bump map kind (0 none,
                    // 1 height, 2 tangent-space normal); z: bump scale (float bits, m per unit);
                    // w: the alpha map's mode (alpha_map.glsl)
};

#include "frame.glsl"
#include "dissolve.glsl"
#include "alpha_map.glsl"
layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
#ifdef MULTIVIEW
// The right eye's frame (view 1 of gbuffer_multiview.frag; view 0 is `frame`).
layout(set = 0, binding = 8, std430) readonly buffer FrameRightBuf { GpuFrame frame_right; };
#define EYE_FRAME(member) (gl_ViewIndex == 0 ? frame.member : frame_right.member)
#define EYE_CAMERA_POSITION EYE_FRAME(camera_position)
#define EYE_CAMERA_FORWARD EYE_FRAME(camera_forward)
#else
#define EYE_CAMERA_POSITION frame.camera_position
#define EYE_CAMERA_FORWARD frame.camera_forward
#define EYE_FRAME(member) frame.member
#endif
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// The draw's albedo texture, or its alpha map when it has no albedo texture (a 1x1 placeholder
// when the material has neither).
layout(set = 0, binding = 2) uniform sampler2D albedo_texture;
// The draw's bump or normal map (the placeholder when it has none).
layout(set = 0, binding = 3) uniform sampler2D bump_texture;
// GGX parameters and emission per material (read only when HAS_GGX or HAS_EMISSION).
struct GpuMaterialPbr {
    vec4 ggx;       // x roughness, y metallic, z 1 for a GGX material
    vec4 emission;  // rgb W/(m^2 sr)
    uvec4 maps;     // 1 where the draw's map is used: x roughness, y metallic, z emission
};
layout(set = 0, binding = 4, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };
// The draw's MTL PBR maps (the placeholder when it has none): roughness and metallic (linear,
// first channel) replace the constants; the emission map (sRGB) multiplies the constant.
layout(set = 0, binding = 5) uniform sampler2D roughness_map;
layout(set = 0, binding = 6) uniform sampler2D metallic_map;
layout(set = 0, binding = 7) uniform sampler2D emission_map;

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

layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_slot2;
layout(location = 3) out vec4 out_slot3;
layout(location = 4) out vec4 out_slot4;

// Tangent frame from screen-space derivatives (Schüler 2013, "Followup: normal mapping
// without precomputed tangents"): no per-vertex tangents needed. uv has v up, as in OBJ.
mat3 cotangent_frame(vec3 n, vec3 p, vec2 uv) {
    vec3 dp1 = dFdx(p), dp2 = dFdy(p);
    vec2 duv1 = dFdx(uv), duv2 = dFdy(uv);
    vec3 dp2perp = cross(dp2, n), dp1perp = cross(n, dp1);
    vec3 t = dp2perp * duv1.x + dp1perp * duv2.x;
    vec3 b = dp2perp * duv1.y + dp1perp * duv2.y;
    float inv = inversesqrt(max(max(dot(t, t), dot(b, b)), 1e-30));
    return mat3(t * inv, b * inv, n);
}

// Height-map bump (Mikkelsen 2010, "Bump mapping unparametrized surfaces on the GPU", eq. 2-4):
// n' = n - surface gradient of the height h (meters), the exact normal of p + h n over a plane.
// Mikkelsen takes h's screen derivatives from dFdx(h), but finite differences of a filtered
// texture across a 2x2 quad are not h's derivatives (bilinear kinks at texel centers, the
// anisotropic footprint): lavapipe gave 0.860 or 0.917 for a ramp whose closed form is 0.894.
// Instead h's gradient is taken in texture space (height_gradient) and carried to the screen
// by the chain rule, dh/dx = grad . dFdx(uv), exact because uv is affine over the triangle.
vec3 bump_height(vec3 n, vec3 p, float dhdx, float dhdy) {
    vec3 dpdx = dFdx(p), dpdy = dFdy(p);
    vec3 r1 = cross(dpdy, n), r2 = cross(n, dpdx);
    float det = dot(dpdx, r1);
    vec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
    return normalize(abs(det) * n - grad);
}

// Gradient of the height map (first channel, map units) per unit of uv, by central differences
// half a texel of the level the sampler would read on either side: the slope across one texel
// of that level, exact for a height linear in uv (every box-filtered mip of a linear ramp is
// the same ramp).
vec2 height_gradient(sampler2D map, vec2 uv) {
    float lod = textureQueryLod(map, uv).x;
    vec2 h = 0.5 * exp2(lod) / vec2(textureSize(map, 0));
    float du = textureLod(map, uv + vec2(h.x, 0.0), lod).r - textureLod(map, uv - vec2(h.x, 0.0), lod).r;
    float dv = textureLod(map, uv + vec2(0.0, h.y), lod).r - textureLod(map, uv - vec2(0.0, h.y), lod).r;
    return vec2(du, dv) / (2.0 * h);
}

void main() {
    GpuMaterial m = materials[pc.material];
    // Before anything that can discard: the threshold takes derivatives.
    float coverage_threshold = HAS_DISSOLVE ? dissolve_threshold(in_world) : 0.0;
    vec3 n = normalize(in_normal);
    // Two-sided surfaces: shade the side the camera sees. Decided geometrically, not by
    // gl_FrontFacing, because the y-flipped projection inverts the winding.
    bool front = dot(n, toward_camera(EYE_CAMERA_POSITION, EYE_CAMERA_FORWARD, in_world)) >= 0.0;
    if (!front) n = -n;
    vec3 albedo = m.albedo.rgb;
    // OBJ texture coordinates have v up; image rows start at the top.
    vec2 tex_uv = vec2(in_uv.x, 1.0 - in_uv.y);
    vec4 texel = HAS_TEXTURES ? texture(albedo_texture, tex_uv) : vec4(1.0);
    if (HAS_TEXTURES && m.flags.x != 0u) albedo = texel.rgb;
    float opacity = HAS_ALPHA_MAP ? alpha_map_opacity(m.flags.w, m.albedo.a, texel.a) : m.albedo.a;
    if (HAS_BUMP && m.flags.y == 2u) {
        vec3 t = texture(bump_texture, tex_uv).xyz * 2.0 - 1.0;
        vec3 bumped = normalize(cotangent_frame(n, in_world, in_uv) * t);
        if (!any(isnan(bumped))) n = bumped;
    } else if (HAS_BUMP && m.flags.y == 1u) {
        vec2 grad = height_gradient(bump_texture, tex_uv) * uintBitsToFloat(m.flags.z);
        vec3 bumped = bump_height(n, in_world, dot(grad, dFdx(tex_uv)), dot(grad, dFdy(tex_uv)));
        if (!any(isnan(bumped))) n = bumped;
    }
    // After the bump's derivatives, which a discarded neighbour would leave undefined.
    float keep = alpha_map_keep_threshold(HAS_DISSOLVE, coverage_threshold);
    if ((HAS_DISSOLVE || HAS_ALPHA_MAP) && opacity < keep) discard;
    vec4 lobe = vec4(m.specular.rgb, 1.0);
    float lobe_parameter = m.specular.a;
    GpuMaterialPbr mp = pbr[pc.material];
    if (HAS_GGX && mp.ggx.z != 0.0) {
        float metallic = mp.ggx.y;
        float roughness = mp.ggx.x;
        if (HAS_PBR_MAPS && mp.maps.y != 0u) metallic = clamp(texture(metallic_map, tex_uv).r, 0.0, 1.0);
        if (HAS_PBR_MAPS && mp.maps.x != 0u) roughness = clamp(texture(roughness_map, tex_uv).r, 0.0, 1.0);
        lobe = vec4(mix(vec3(0.04), albedo, metallic), 2.0);
        lobe_parameter = roughness;
        albedo *= 1.0 - metallic;
    }
    out_albedo = vec4(albedo, 1.0);
    out_normal = vec4(n, lobe_parameter);
    // Emission leaves the front side only, as Mitsuba's area emitter.
    vec3 emitted = mp.emission.rgb;
    if (HAS_PBR_MAPS && mp.maps.z != 0u) emitted *= texture(emission_map, tex_uv).rgb;
    // The attachment is half float: it holds the pre-exposed emission (frame.glsl's
    // radiance_scale; ×1 in almost every scene), which deferred_direct scales back.
    vec4 emission = vec4(front ? emitted * frame.radiance_scale.x : vec3(0.0), 1.0);
    if (HAS_LOBE) out_slot2 = lobe;
    if (HAS_EMISSION && HAS_LOBE) out_slot3 = emission;
    if (HAS_EMISSION && !HAS_LOBE) out_slot2 = emission;
    if (HAS_MOTION) {
        // The motion vector: where this surface point was on the previous frame's screen
        // (its world position moved back by the draw's motion, seen by the previous
        // un-jittered camera) minus where it is now without this frame's jitter, in NDC. A
        // point behind the previous camera gets an offset far off the screen (no history).
        vec4 now = EYE_FRAME(view_proj) * vec4(in_world, 1.0);
        vec3 prev_world = vec4(in_world, 1.0) * pc.motion;
        vec4 then = EYE_FRAME(prev_view_proj) * vec4(prev_world, 1.0);
        vec2 moved = then.w > 1e-6 ? then.xy / then.w - (now.xy / now.w - EYE_FRAME(jitter_ndc).xy) : vec2(4.0);
        vec4 motion = vec4(moved, 0.0, 0.0);
        int slot = 2 + int(HAS_LOBE) + int(HAS_EMISSION);
        if (slot == 2) out_slot2 = motion;
        if (slot == 3) out_slot3 = motion;
        if (slot == 4) out_slot4 = motion;
    }
}

#version 450
// Reflective light maps: what the light sees (through any view: spot, cube face, orthographic
// or an area-light element's paraboloid, light_map.geom) is directly lit by it, so each texel stores the
// radiance leaving that surface (Lambert: rho/pi * E, E = I cos / d^2 with Mitsuba's spot
// falloff; the diffuse part), its world position and material and its normal, for lookups at
// voxel ray hits (Thiedemann 2010, §6.3.3). A GGX sender's diffuse part is
// (1 - m) b / pi (1 - F_d(n.wi)) E (brdf.glsl's brdf_ggx without the factor (1 - F_d(n.wo))
// toward the receiver, which the map cannot know). What a lookup needs to evaluate a glossy
// sender's whole BRDF toward its receiver is in the texel without further targets: the
// position's w names the material (Phong rho_s and exponent, GGX base color, roughness and
// metalness), the layer names the view and so the light (its position or direction, and E
// recomputed as here), and the normal is stored; gi_hemisphere_body.glsl and
// gi_vpl_generate.comp add the lobes.
// With HAS_MAPS (a drawn material has map_Kd, or a GGX one map_Pm) the texel samples the
// draw's albedo texture (replacing Kd) and metalness map (replacing Pm) as the G-buffer does:
// the same textures and sampler, the level from this texel's own footprint (derivatives of the
// texture coordinates across the light map). A lookup's lobe still takes the material's
// constants (base color, roughness, metalness): see docs/ARCHITECTURE.md, "Materials".
#include "frame.glsl"
#include "dissolve.glsl"
#include "alpha_map.glsl"
#include "paraboloid.glsl"

// Some material has MTL d < 1: its texels are covered as in the shadow maps (dissolve.glsl).
layout(constant_id = 0) const bool HAS_DISSOLVE = false;
layout(constant_id = 1) const bool HAS_GGX = false;
layout(constant_id = 3) const bool HAS_MAPS = false;
// Some material has an alpha map (alpha_map.glsl) in the alpha of binding 3 (HAS_MAPS is then
// set too): its texels are cut or thinned as in the shadow maps.
layout(constant_id = 4) const bool HAS_ALPHA_MAP = false;

layout(set = 0, binding = 0, std430) readonly buffer FrameBuf { GpuFrame frame; };
struct GpuMaterial { vec4 albedo; vec4 specular; uvec4 flags; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { GpuMaterial materials[]; };
// GGX parameters per material (gbuffer.frag's table; read only when HAS_GGX).
struct GpuMaterialPbr { vec4 ggx; vec4 emission; uvec4 maps; };
layout(set = 0, binding = 2, std430) readonly buffer MaterialsPbr { GpuMaterialPbr pbr[]; };
// The draw's albedo texture (flags.x) and metalness map (maps.y), the scene's placeholder where
// it has none; read only with HAS_MAPS.
layout(set = 0, binding = 3) uniform sampler2D albedo_texture;
layout(set = 0, binding = 4) uniform sampler2D metallic_map;

layout(push_constant) uniform Push {
    mat4 model;
    uint view;
    uint material;
    uint layer_base;
} pc;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec3 in_world;
// Paraboloid views (light_map.geom; w of in_v0 is 1 there).
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in vec4 in_v0;
layout(location = 4) flat in vec3 in_v1;
layout(location = 5) flat in vec3 in_v2;
layout(location = 6) flat in vec3 in_w0;
layout(location = 7) flat in vec3 in_w1;
layout(location = 8) flat in vec3 in_w2;
layout(location = 9) flat in vec3 in_n0;
layout(location = 10) flat in vec3 in_n1;
layout(location = 11) flat in vec3 in_n2;
layout(location = 12) flat in vec4 in_range_t2;
layout(location = 13) in vec2 in_tex_uv;
layout(location = 14) flat in vec4 in_t01;

layout(location = 0) out vec4 out_radiance;
layout(location = 1) out vec4 out_position;
layout(location = 2) out vec4 out_normal;

#define PI 3.14159265358979323846

void main() {
    vec3 world = in_world;
    vec3 normal = in_normal;
    bool covered = true;
    gl_FragDepth = gl_FragCoord.z;
    vec2 tex_uv = in_tex_uv;
    if (in_v0.w != 0.0) {
        // A paraboloid view: the exact hit of this texel's ray (paraboloid.glsl), its world
        // position and normal from the barycentric weights, its radial depth.
        vec3 dir, bary;
        float dist;
        covered = paraboloid_ray(in_uv, in_v0.xyz, in_v1, in_v2, dir, dist, bary);
        world = bary.x * in_w0 + bary.y * in_w1 + bary.z * in_w2;
        normal = bary.x * in_n0 + bary.y * in_n1 + bary.z * in_n2;
        tex_uv = bary.x * in_t01.xy + bary.y * in_t01.zw + bary.z * in_range_t2.zw;
        vec2 range = in_range_t2.xy;
        gl_FragDepth = clamp((dist - range.x) / (range.y - range.x), 0.0, 1.0);
    }
    // Before any discard: the threshold and the maps' footprint take derivatives. Image rows
    // start at the top (OBJ's v points up), as in the G-buffer.
    float coverage_threshold = HAS_DISSOLVE ? dissolve_threshold(world) : 0.0;
    vec2 st = vec2(tex_uv.x, 1.0 - tex_uv.y);
    vec2 st_dx = vec2(0.0), st_dy = vec2(0.0);
    if (HAS_MAPS) {
        st_dx = dFdx(st);
        st_dy = dFdy(st);
    }
    if (!covered) discard;
    // The shadow views index their light through the light table.
    GpuLight l;
    for (uint i = 0u; i < frame.counts.x; ++i) {
        GpuLight c = frame.lights[i];
        if (pc.view >= c.info.y && pc.view < c.info.y + c.info.z) l = c;
    }
    vec3 n = normalize(normal);
    vec3 e;
    float cos_i;
    if (l.info.x == LIGHT_DIRECTIONAL) {
        if (dot(n, -l.direction.xyz) < 0.0) n = -n;
        cos_i = max(dot(n, -l.direction.xyz), 0.0);
        e = l.intensity.rgb * cos_i;
    } else {
        vec3 d = l.position.xyz - world;
        float d2 = max(dot(d, d), 1e-30);
        vec3 wi = d * inversesqrt(d2);
        // Two-sided: the side the light sees.
        if (dot(n, wi) < 0.0) n = -n;
        float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
        cos_i = max(dot(n, wi), 0.0);
        e = l.intensity.rgb * (falloff * cos_i / d2);
    }
    GpuMaterial m = materials[pc.material];
    vec4 texel = HAS_MAPS ? textureGrad(albedo_texture, st, st_dx, st_dy) : vec4(1.0);
    float opacity = HAS_ALPHA_MAP ? alpha_map_opacity(m.flags.w, m.albedo.a, texel.a) : m.albedo.a;
    float keep = alpha_map_keep_threshold(HAS_DISSOLVE, coverage_threshold);
    if ((HAS_DISSOLVE || HAS_ALPHA_MAP) && opacity < keep) discard;
    vec3 diffuse = m.albedo.rgb;
    if (HAS_MAPS && m.flags.x != 0u) diffuse = texel.rgb;
    if (HAS_GGX && pbr[pc.material].ggx.z != 0.0) {
        // Schlick with F0 = 0.04 (brdf.glsl's fresnel_schlick), inlined.
        float f_d = 0.04 + 0.96 * pow(1.0 - clamp(cos_i, 0.0, 1.0), 5.0);
        float metallic = pbr[pc.material].ggx.y;
        if (HAS_MAPS && pbr[pc.material].maps.y != 0u) {
            metallic = clamp(textureGrad(metallic_map, st, st_dx, st_dy).r, 0.0, 1.0);
        }
        diffuse *= (1.0 - metallic) * (1.0 - f_d);
    }
    out_radiance = vec4(diffuse / PI * e, 1.0);
    // w: material index + 1 (0 marks texels the light sees nothing in), so lookups can
    // evaluate a glossy sender's lobe toward the ray (§6.4.3).
    out_position = vec4(world, float(pc.material + 1u));
    out_normal = vec4(n, 0.0);
}

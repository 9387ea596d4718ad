#version 450
// Non-binary atlas voxelization (Thiedemann 2010, §4.3.2): one vertex per atlas point (vertex pulling, no
// vertex buffer), drawn as a point list. The point goes to the same voxel as its bit in
// voxelize_atlas.comp (atlas_voxel.glsl); its raster position is that voxel's column centre
// (the viewport is the grid's x,y resolution) and the geometry shader routes it to the layer
// of its depth index. It carries its triangle's material albedo and world-space face normal,
// computed like voxelize_attributes.comp so both voxelizers feed the path tracer alike, and
// with value volumes (src/voxel/gpu_atlas_volumes.rs) its emission and material lobe, the
// maps sampled at the point (HAS_MAPS, voxel_maps.glsl: map_Kd replacing the albedo, map_Ke,
// map_Pr, map_Pm) as the triangle voxelizer's voxel_owner_maps.glsl samples them.
#include "atlas_voxel.glsl"

layout(constant_id = 0) const bool HAS_EMISSION = false;
layout(constant_id = 1) const bool HAS_MATERIAL = false;
layout(constant_id = 2) const bool HAS_MAPS = false;

struct Triangle {
    vec4 v[3];   // model-space vertices; w of v[0..2] = the material's albedo r, g, b
};
layout(set = 0, binding = 0, std430) readonly buffer Points { uvec4 points[]; };
layout(set = 0, binding = 1, std430) readonly buffer Triangles { Triangle tris[]; };
// With value volumes or maps, per triangle five vec4s: emission (rgb W/(m^2 sr) = Ke, times
// map_Ke with HAS_MAPS; w 1 for an emissive material), the material texel (material_texel),
// then its GpuTriangleMaps (voxel_maps.glsl). Bound to the triangles otherwise (never read).
layout(set = 0, binding = 2, std430) readonly buffer Values { vec4 values[]; };
#define VOXEL_MAPS_TEXELS_BINDING 3
#define VOXEL_MAPS_TABLE_BINDING 4
#include "voxel_maps.glsl"
// A point its surface's coverage drops writes no attribute, as it sets no bit.
#define ATLAS_COVERAGE_BINDING 5
#include "voxel_coverage.glsl"

layout(push_constant) uniform Push {
    mat4 model;      // model -> world
    vec4 grid_min;   // world corner of the grid box (xyz)
    vec4 scale;      // voxels per meter in the voxel-camera frame (u, v, w)
    uvec4 dims;      // res_x, res_y, D, depth axis (0 = X, 1 = Y, 2 = Z)
    uvec4 extent;    // w, 1: coverage bound (xyz: the compute twin's column-buffer size, count)
} pc;

layout(location = 0) flat out int v_layer;   // depth index k, -1 outside the grid
layout(location = 1) flat out vec3 v_albedo;
layout(location = 2) flat out vec4 v_normal;     // w: 1 for a Phong or GGX point
layout(location = 3) flat out vec4 v_emission;   // rgb radiance, w: 1 for an emitter's point
layout(location = 4) flat out vec4 v_material;   // the material texel (0 for Lambert)

// The point's barycentric weights on its (model-space) triangle, clamped to it: atlas points
// are the triangle's points nearest their texels, so on it up to rounding.
vec3 barycentric(vec3 p, Triangle t) {
    vec3 e0 = t.v[1].xyz - t.v[0].xyz, e1 = t.v[2].xyz - t.v[0].xyz, d = p - t.v[0].xyz;
    float d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1);
    float d20 = dot(d, e0), d21 = dot(d, e1);
    float den = d00 * d11 - d01 * d01;
    if (!(abs(den) > 0.0)) return vec3(1.0, 0.0, 0.0);
    float w1 = (d11 * d20 - d01 * d21) / den;
    float w2 = (d00 * d21 - d01 * d20) / den;
    vec3 w = max(vec3(1.0 - w1 - w2, w1, w2), vec3(0.0));
    return w / max(w.x + w.y + w.z, 1e-30);
}

void main() {
    uvec4 pt = points[gl_VertexIndex];
    vec3 p = uintBitsToFloat(pt.xyz);
    uvec3 voxel;
    bool inside = atlas_point_voxel(pc.model, p, pc.grid_min.xyz, pc.scale.xyz, pc.dims, voxel)
               && atlas_point_covers(voxel, pt.w, pc.extent.w);
    v_layer = inside ? int(voxel.z) : -1;
    // The column centre: a size-1 point there covers exactly pixel (voxel.x, voxel.y).
    vec2 ndc = (vec2(voxel.xy) + 0.5) / vec2(pc.dims.xy) * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.5, 1.0);
    Triangle t = tris[pt.w];
    vec3 w0 = (pc.model * vec4(t.v[0].xyz, 1.0)).xyz;
    vec3 w1 = (pc.model * vec4(t.v[1].xyz, 1.0)).xyz;
    vec3 w2 = (pc.model * vec4(t.v[2].xyz, 1.0)).xyz;
    vec3 n = cross(w1 - w0, w2 - w0);
    v_normal = vec4(dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 1.0, 0.0), 0.0);
    v_albedo = vec3(t.v[0].w, t.v[1].w, t.v[2].w);
    v_emission = vec4(0.0);
    v_material = vec4(0.0);
    if (!HAS_EMISSION && !HAS_MATERIAL && !HAS_MAPS) return;
    uint row = 5u * pt.w;
    v_emission = values[row];
    v_material = values[row + 1u];
    if (HAS_MAPS) {
        vec4 uv01 = values[row + 2u];
        vec4 uv2_lod = values[row + 3u];
        ivec4 maps = floatBitsToInt(values[row + 4u]);
        if (any(greaterThanEqual(maps, ivec4(0)))) {
            vec2 uv = voxel_map_uv(uv01, uv2_lod, barycentric(p, t));
            float lod = uv2_lod.z;
            // map_Kd replaces Kd, as in the G-buffer.
            if (maps.w >= 0) v_albedo = sample_voxel_map(maps.w, uv, lod).rgb;
            if (HAS_EMISSION && maps.z >= 0) v_emission.rgb *= sample_voxel_map(maps.z, uv, lod).rgb;
            if (HAS_MATERIAL && maps.x >= 0) v_material.r = clamp(sample_voxel_map(maps.x, uv, lod).r, 0.0, 1.0);
            if (HAS_MATERIAL && maps.y >= 0) v_material.g = clamp(sample_voxel_map(maps.y, uv, lod).r, 0.0, 1.0);
        }
    }
    v_normal.w = v_material.w != 0.0 ? 1.0 : 0.0;
}

// The maps of a voxel's owner triangle averaged over the owner's part of the voxel, for the
// triangle voxelizer's passes that write per-owner values (voxelize_owner_value.glsl: emission,
// material; voxelize_attributes_resolve.comp: albedo). 4 x 4 points on the voxel's face across
// the triangle's dominant normal axis, projected along that axis onto the triangle's plane (a
// parallel projection scales every area of the plane alike, so equally spaced points weigh
// equal areas); points outside the triangle or the voxel drop out. A sliver that no point hits
// takes the triangle's point nearest the voxel's centre (barycentric weights clamped).
// The includer declares `tris[]` (world-space vertices in v[0..2].xyz), the push block `pc`
// (GpuVoxelizePush: grid_min, scale, dims) and includes voxel_maps.glsl first.
#ifndef VOXEL_OWNER_MAPS_GLSL
#define VOXEL_OWNER_MAPS_GLSL

// World point -> continuous voxel coordinates (VoxelGrid::world_to_voxel).
vec3 owner_to_voxel(vec3 p) {
    vec3 d = p - pc.grid_min.xyz;
    vec3 f = pc.dims.w == 0u ? d.yzx : (pc.dims.w == 1u ? d.zxy : d);
    return f * pc.scale.xyz;
}

// The owner's maps averaged over its part of voxel v (see the top): rgba of every map in
// `maps` (one per row: roughness, metallic, emission, albedo; -1 none).
void owner_map_means(uint owner, ivec3 v, vec4 uv01, vec4 uv2_lod, ivec4 maps,
                     out vec4 mean_r, out vec4 mean_m, out vec4 mean_e, out vec4 mean_a) {
    Triangle t = tris[owner];
    vec3 a = owner_to_voxel(t.v[0].xyz) - vec3(v);
    vec3 b = owner_to_voxel(t.v[1].xyz) - vec3(v);
    vec3 c = owner_to_voxel(t.v[2].xyz) - vec3(v);
    vec3 n = cross(b - a, c - a);
    vec3 an = abs(n);
    // The dominant axis d and the face axes (i, j).
    int d = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    int i = (d + 1) % 3;
    int j = (d + 2) % 3;
    vec2 a2 = vec2(a[i], a[j]), b2 = vec2(b[i], b[j]), c2 = vec2(c[i], c[j]);
    float area2 = (b2.x - a2.x) * (c2.y - a2.y) - (b2.y - a2.y) * (c2.x - a2.x);
    float lod = uv2_lod.z;
    mean_r = vec4(0.0);
    mean_m = vec4(0.0);
    mean_e = vec4(0.0);
    mean_a = vec4(0.0);
    float count = 0.0;
    if (an[d] > 0.0 && area2 != 0.0) {
        float plane = dot(n, a);
        for (int s = 0; s < 16; s++) {
            vec2 q = (vec2(s % 4, s / 4) + 0.5) * 0.25;
            float qd = (plane - n[i] * q.x - n[j] * q.y) / n[d];
            if (qd < 0.0 || qd > 1.0) continue;
            // Barycentric weights in the face's projection (exact for points of the plane).
            float w1 = ((q.x - a2.x) * (c2.y - a2.y) - (q.y - a2.y) * (c2.x - a2.x)) / area2;
            float w2 = ((b2.x - a2.x) * (q.y - a2.y) - (b2.y - a2.y) * (q.x - a2.x)) / area2;
            vec3 w = vec3(1.0 - w1 - w2, w1, w2);
            if (any(lessThan(w, vec3(0.0)))) continue;
            vec2 uv = voxel_map_uv(uv01, uv2_lod, w);
            if (maps.x >= 0) mean_r += sample_voxel_map(maps.x, uv, lod);
            if (maps.y >= 0) mean_m += sample_voxel_map(maps.y, uv, lod);
            if (maps.z >= 0) mean_e += sample_voxel_map(maps.z, uv, lod);
            if (maps.w >= 0) mean_a += sample_voxel_map(maps.w, uv, lod);
            count += 1.0;
        }
    }
    if (count > 0.0) {
        mean_r /= count;
        mean_m /= count;
        mean_e /= count;
        mean_a /= count;
        return;
    }
    // A sliver: the voxel centre's barycentric weights in the face's projection, clamped.
    vec2 q = vec2(0.5);
    vec3 w = vec3(1.0, 0.0, 0.0);
    if (area2 != 0.0) {
        float w1 = ((q.x - a2.x) * (c2.y - a2.y) - (q.y - a2.y) * (c2.x - a2.x)) / area2;
        float w2 = ((b2.x - a2.x) * (q.y - a2.y) - (b2.y - a2.y) * (q.x - a2.x)) / area2;
        w = max(vec3(1.0 - w1 - w2, w1, w2), vec3(0.0));
        w /= max(w.x + w.y + w.z, 1e-30);
    }
    vec2 uv = voxel_map_uv(uv01, uv2_lod, w);
    if (maps.x >= 0) mean_r = sample_voxel_map(maps.x, uv, lod);
    if (maps.y >= 0) mean_m = sample_voxel_map(maps.y, uv, lod);
    if (maps.z >= 0) mean_e = sample_voxel_map(maps.z, uv, lod);
    if (maps.w >= 0) mean_a = sample_voxel_map(maps.w, uv, lod);
}

#endif

// Next-event estimation toward the scene's emissive triangles (src/gi/emitters.rs builds the
// list): a triangle picked by power, a point uniformly on it, visibility by the voxel ray test,
// and multiple importance sampling with the power heuristic (Veach 1997, §9.2.4) against the
// BSDF-sampled ray that may hit the same emitter in the voxels.
//
// The light strategy's density per unit area, p_A = w(L) / sum_t w(L_t) A_t (w the mean of
// the radiance's channels), depends only on the emitted radiance L at the point; a BSDF ray
// that hits an emitting voxel reads L from the emission volume and so knows p_A without
// knowing the triangle (emitter_hit_weight). Both weights are then functions of the same
// point, and they sum to 1 wherever the voxel emitter and the triangle agree: the combination
// is unbiased up to the voxelization's own difference (docs/design/emitter-sampling.md).
//
// Shared by the path tracer (gi_pathtrace.comp) and the emitters' direct light
// (direct_emitters.comp). Needs before it: EMITTERS_BINDING, gi_common.glsl (the push
// constants), voxel_traverse.glsl (voxel_visible), material_lobe.glsl (Lobe, lobe_pdf,
// lobe_part_brdf, lobe_brdf).
#ifndef EMITTERS_GLSL
#define EMITTERS_GLSL

struct GpuEmitterHeader {
    uint count;               // rows
    float inv_weighted_area;  // 1 / sum_t w(L_t) A_t; 0: every triangle is black
    uvec2 pad;
};

struct GpuEmissiveTriangle {
    vec4 origin;    // a vertex (m); w the CDF of the power up to and including this row
    vec4 edge1;     // to the second vertex (m); w the probability of picking this row
    vec4 edge2;     // to the third vertex (m); the emitting side is edge1 x edge2's
    vec4 radiance;  // L (W/(m^2 sr)); w its area density p_A (1/m^2)
};

layout(set = 0, binding = EMITTERS_BINDING, std430) readonly buffer Emitters {
    GpuEmitterHeader emitter_header;
    GpuEmissiveTriangle emitter_rows[];
};

// The power heuristic's weight of the strategy of density a against one of density b
// (a^2 / (a^2 + b^2), as a ratio so that the huge densities of narrow lobes do not overflow).
float mis_power(float a, float b) {
    if (b <= 0.0) return 1.0;
    if (a <= 0.0) return 0.0;
    float r = b / a;
    return 1.0 / (1.0 + r * r);
}

// The MIS weight of a BSDF-sampled ray of density pdf_bsdf (solid angle) that hit an emitting
// voxel of radiance le at distance dist_m, arriving at cos_l to the voxel's normal: the light
// strategy would have drawn that point with p_A(le) dist^2 / cos_l.
float emitter_hit_weight(vec3 le, float dist_m, float cos_l, float pdf_bsdf) {
    float pa = (le.r + le.g + le.b) / 3.0 * emitter_header.inv_weighted_area;
    if (pa <= 0.0) return 1.0;
    return mis_power(pdf_bsdf, pa * dist_m * dist_m / max(cos_l, 1e-6));
}

// Whether emitter point y (normal nl) is visible from the vertex o along wi (ci = n.wi): the
// segment leaves o as the BSDF rays do (k2 h / (d.n), clamped) and stops k1 voxel diagonals
// off the emitter along its normal, as the rays start off their own surface (Thiedemann 2010
// §5.3.1), so neither end's own voxels block it.
bool emitter_point_visible(vec3 o, vec3 wi, float ci, vec3 y, vec3 nl) {
    float along = min(gi.ray_offset_voxels * gi.voxel_diagonal_m / max(ci, 1e-4),
        gi.ray_offset_max_voxels * gi.voxel_diagonal_m);
    vec3 start = o + wi * along;
    vec3 end = y + nl * (gi.normal_offset_voxels * gi.voxel_diagonal_m);
    if (dot(end - start, wi) <= 0.0) return true;
    vec3 a_v = (gi.world_to_voxel * vec4(start, 1.0)).xyz;
    vec3 b_v = (gi.world_to_voxel * vec4(end, 1.0)).xyz;
    return voxel_visible(gi.dims, uint(gi.max_level), a_v, b_v, gi.start_level, gi.max_iterations);
}

// One light sample at the path vertex o (normal n, wo toward where the path came from,
// material m), u uniform in [0,1)^2: the MIS-weighted estimate of the radiance the vertex
// reflects toward wo from the emissive triangles, f L cos_i cos_l / (d^2 p_A) per sampled lobe
// part. `parts`: 0 the diffuse part only, 1 the specular part only (the first bounce's
// stratified split, each half its own estimator), 2 both, where the BSDF sample picks the
// specular part with probability ps (its density is then ps times that part's);
// 3 the whole BRDF, unweighted (direct_emitters.comp's Lambert pixels: no BSDF strategy to
// combine with); 4 the diffuse part unweighted and the specular part weighted against the
// specular lobe's samples of emitter_lobe_hit, ps their count per light sample
// (direct_emitters.comp's Phong and GGX pixels).
vec3 emitter_sample_from(vec3 g, vec3 o, vec3 n, vec3 wo, Lobe m, uint parts, float ps, vec2 u);

vec3 emitter_sample(vec3 o, vec3 n, vec3 wo, Lobe m, uint parts, float ps, vec2 u) {
    return emitter_sample_from(o, o, n, wo, m, parts, ps, u);
}

// emitter_sample with the light's geometry (distance and both cosines) taken at the surface
// point g, the distance no less than the offset |o - g|, and its visibility tested from the
// offset origin o, which stays off the surface's own voxels.
vec3 emitter_sample_from(vec3 g, vec3 o, vec3 n, vec3 wo, Lobe m, uint parts, float ps, vec2 u) {
    uint count = emitter_header.count;
    if (count == 0u || emitter_header.inv_weighted_area <= 0.0) return vec3(0.0);
    // The first row whose CDF exceeds u.x.
    uint lo = 0u, hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (emitter_rows[mid].origin.w > u.x) hi = mid;
        else lo = mid + 1u;
    }
    GpuEmissiveTriangle e = emitter_rows[lo];
    float pick = e.edge1.w;
    float pa = e.radiance.w;
    if (pick <= 0.0 || pa <= 0.0) return vec3(0.0);
    // u.x rescaled within the row's interval picks the point with u.y (stratification kept):
    // uniform on the triangle by the square-root map (Pharr, Jakob and Humphreys 2016, §13.6.5).
    float below = lo == 0u ? 0.0 : emitter_rows[lo - 1u].origin.w;
    float a = clamp((u.x - below) / pick, 0.0, 1.0);
    float su = sqrt(a);
    vec3 y = e.origin.xyz + e.edge1.xyz * (su * (1.0 - u.y)) + e.edge2.xyz * (su * u.y);
    vec3 nl = cross(e.edge1.xyz, e.edge2.xyz);
    float nl_len = length(nl);
    vec3 to = y - g;
    float d2 = dot(to, to);
    if (nl_len <= 0.0 || d2 <= 0.0) return vec3(0.0);
    nl /= nl_len;
    float dist = sqrt(d2);
    vec3 wi = to / dist;
    float ci = dot(n, wi);
    float cl = -dot(nl, wi);
    // Below the vertex's surface, behind the emitter's front, or beyond the GI rays' reach.
    if (ci <= 0.0 || cl <= 0.0 || dist > gi.radius_m) return vec3(0.0);
#ifdef EMITTER_POINT_SKIPPED
    // The includer brings this point's light another way (direct_emitters.comp under
    // screen-space GI: the emitting points the camera sees, which the gather reads).
    if (EMITTER_POINT_SKIPPED(y, nl)) return vec3(0.0);
#endif
    // 1/d^2 is capped at the origin's offset |o - g|: where a surface touches an emitter (a
    // window's reveal at its edge) the integrand's singularity makes fireflies of a few
    // samples, which the offset bounded before the geometry moved to the surface point.
    d2 = max(d2, dot(o - g, o - g));
    float pl = pa * d2 / cl;
    vec3 f = vec3(0.0);
    if (parts == 3u) {
        f = lobe_brdf(m, n, wi, wo);
    } else if (parts == 4u) {
        f = lobe_part_brdf(m, n, wi, wo, false)
            + lobe_part_brdf(m, n, wi, wo, true) * mis_power(pl, ps * lobe_pdf(m, n, wo, wi, true));
    } else {
        if (parts != 1u) {
            float pd = (parts == 2u ? 1.0 - ps : 1.0) * lobe_pdf(m, n, wo, wi, false);
            f += lobe_part_brdf(m, n, wi, wo, false) * mis_power(pl, pd);
        }
        if (parts != 0u) {
            float pspec = (parts == 2u ? ps : 1.0) * lobe_pdf(m, n, wo, wi, true);
            f += lobe_part_brdf(m, n, wi, wo, true) * mis_power(pl, pspec);
        }
    }
    if (all(equal(f, vec3(0.0)))) return vec3(0.0);
    vec3 wv = normalize(y - o);
    if (!emitter_point_visible(o, wv, max(dot(n, wv), 0.0), y, nl)) return vec3(0.0);
    return f * e.radiance.rgb * (ci * cl / (d2 * pa));
}

// The BSDF strategy that emitter_sample's parts 4 is weighted against, for a vertex that has
// no emission volume to read (direct_emitters.comp): the specular lobe's sample wi (weight w,
// sample_lobe's f cos / pdf) is intersected with every emitting triangle (Moeller and Trumbore
// 1997), and the nearest front face hit within the rays' reach, visible by the same voxel
// segment as a light sample's, brings w L times the power heuristic's weight against the light
// strategy, whose density there is p_A d^2 / cos_l (ps: these samples per light sample). The
// loop is over all rows: fine for the tens to hundreds of triangles of a scene's lamps.
vec3 emitter_lobe_hit(vec3 o, vec3 n, vec3 wo, Lobe m, vec3 wi, vec3 w, float ps) {
    uint count = emitter_header.count;
    float ci = dot(n, wi);
    if (count == 0u || emitter_header.inv_weighted_area <= 0.0 || ci <= 0.0) return vec3(0.0);
    float best = gi.radius_m;
    int hit = -1;
    for (uint r = 0u; r < count; ++r) {
        GpuEmissiveTriangle e = emitter_rows[r];
        vec3 pv = cross(wi, e.edge2.xyz);
        float det = dot(e.edge1.xyz, pv);
        // det = -wi . (edge1 x edge2): positive only where wi meets the emitting side.
        if (det <= 1e-12) continue;
        vec3 tv = o - e.origin.xyz;
        float bu = dot(tv, pv) / det;
        if (bu < 0.0 || bu > 1.0) continue;
        vec3 qv = cross(tv, e.edge1.xyz);
        float bv = dot(wi, qv) / det;
        if (bv < 0.0 || bu + bv > 1.0) continue;
        float t = dot(e.edge2.xyz, qv) / det;
        if (t > 0.0 && t < best) {
            best = t;
            hit = int(r);
        }
    }
    if (hit < 0) return vec3(0.0);
    GpuEmissiveTriangle e = emitter_rows[hit];
    float pa = e.radiance.w;
    if (pa <= 0.0) return vec3(0.0);
    vec3 nl = normalize(cross(e.edge1.xyz, e.edge2.xyz));
    float cl = -dot(nl, wi);
    vec3 y = o + wi * best;
#ifdef EMITTER_POINT_SKIPPED
    if (EMITTER_POINT_SKIPPED(y, nl)) return vec3(0.0);
#endif
    if (!emitter_point_visible(o, wi, ci, y, nl)) return vec3(0.0);
    float pl = pa * best * best / max(cl, 1e-6);
    return w * e.radiance.rgb * mis_power(ps * lobe_pdf(m, n, wo, wi, true), pl);
}

#endif

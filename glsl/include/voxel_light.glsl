// The irradiance a light puts on a voxel's surface, as the direct-radiance volume computes it
// (Thiedemann 2010, §6.3.2): `gi_radiance_volume.comp` for the diffuse part it stores, and
// `gi_hemisphere_volume.comp` for a glossy voxel's specular lobe at a ray's hit, so both see
// the same E. Needs frame.glsl and the including shader's `gi` push block.
#ifndef VOXEL_LIGHT_GLSL
#define VOXEL_LIGHT_GLSL

// E from light `l` at voxel center `p` on the side of unit normal `ns`, before visibility
// (E = I cos / d^2 with the spot falloff, or E_perp cos); `wi` the unit direction toward the
// light.
vec3 voxel_light_e(GpuLight l, vec3 p, vec3 ns, out vec3 wi) {
    if (l.info.x == LIGHT_DIRECTIONAL) {
        wi = -l.direction.xyz;
        return l.intensity.rgb * max(dot(ns, wi), 0.0);
    }
    vec3 d = l.position.xyz - p;
    float d2 = max(dot(d, d), 1e-30);
    wi = d * inversesqrt(d2);
    float falloff = light_falloff(l, dot(-wi, l.direction.xyz));
    return l.intensity.rgb * (falloff * max(dot(ns, wi), 0.0) / d2);
}

// The shadow-map visibility of `l` for that side: looked up a voxel diagonal off the voxel
// center, so the surface inside the voxel does not shadow itself.
float voxel_light_visibility(sampler2DArray maps, GpuLight l, vec3 p, vec3 ns, vec3 wi) {
    return shadow_visibility(maps, l, p + ns * gi.voxel_diagonal_m, ns, max(dot(ns, wi), 0.0));
}

#endif

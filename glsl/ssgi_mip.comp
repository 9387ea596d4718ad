#version 450
// One level of the screen-space GI pyramids from the level below (Oetke 2017 §5.3): the lit
// colour is the 2x2 box average (the thesis's linear blit); position and normal are copied
// from one of the 2x2 children, chosen by SHR10's voting filter as the thesis approximates
// it: the children are scored against the mean view depth and normal of the 4x4
// neighbourhood, s = g1(Δn.x) g1(Δn.y) g1(Δn.z) g2(Δz) with Gaussians of σ = 0.1 (normal
// components) and σ = 1% of the mean depth (the thesis's 0.001 of normalized depth, made
// relative), the highest score wins (ties go to the last child). Without VOTING the first
// non-sky child wins (the thesis's fast nearest-neighbour blit).
layout(constant_id = 0) const bool VOTING = true;

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D in_pos;
layout(set = 0, binding = 1) uniform sampler2D in_nrm;
layout(set = 0, binding = 2) uniform sampler2D in_color;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D out_pos;
layout(set = 0, binding = 4, rgba16f) uniform writeonly image2D out_nrm;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2D out_color;

float gauss(float x, float sigma) {
    return exp(-x * x / (2.0 * sigma * sigma));
}

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, imageSize(out_pos)))) return;
    ivec2 fine = textureSize(in_pos, 0);
    vec3 color = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        color += texelFetch(in_color, min(2 * q + ivec2(k & 1, k >> 1), fine - 1), 0).rgb;
    }
    imageStore(out_color, q, vec4(0.25 * color, 1.0));

    // The 4x4 neighbourhood's mean depth and normal over its non-sky texels.
    float z_mean = 0.0, count = 0.0;
    vec3 n_mean = vec3(0.0);
    if (VOTING) {
        for (int y = -1; y <= 2; ++y) {
            for (int x = -1; x <= 2; ++x) {
                ivec2 s = clamp(2 * q + ivec2(x, y), ivec2(0), fine - 1);
                float z = texelFetch(in_pos, s, 0).w;
                if (z <= 0.0) continue;
                z_mean += z;
                n_mean += texelFetch(in_nrm, s, 0).xyz;
                count += 1.0;
            }
        }
        z_mean /= max(count, 1.0);
        n_mean /= max(count, 1.0);
    }
    int best = -1;
    float best_score = -1.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 c = min(2 * q + ivec2(k & 1, k >> 1), fine - 1);
        float z = texelFetch(in_pos, c, 0).w;
        if (z <= 0.0) continue;
        if (!VOTING) {
            best = k;
            break;
        }
        vec3 dn = texelFetch(in_nrm, c, 0).xyz - n_mean;
        float s = gauss(dn.x, 0.1) * gauss(dn.y, 0.1) * gauss(dn.z, 0.1)
                * gauss(z - z_mean, 0.01 * z_mean);
        if (s >= best_score) {
            best_score = s;
            best = k;
        }
    }
    if (best < 0) {
        imageStore(out_pos, q, vec4(0.0));
        imageStore(out_nrm, q, vec4(0.0));
        return;
    }
    ivec2 c = min(2 * q + ivec2(best & 1, best >> 1), fine - 1);
    imageStore(out_pos, q, texelFetch(in_pos, c, 0));
    imageStore(out_nrm, q, texelFetch(in_nrm, c, 0));
}

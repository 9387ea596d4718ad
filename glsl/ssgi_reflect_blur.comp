#version 450
// The screen-space reflections' small blur (Oetke 2017 §5.4): a 3x3 binomial filter of the
// traced, temporally blended (a·L, a) over the neighbours on the same surface, each weighted
// as the joint bilateral upsampling weights its texels (normal agreement to the 8th power,
// a Gaussian of the view depths' difference at 5% of the depth), Lambert and sky neighbours
// left out. Also copies the unblurred value into the history the next frame's ssgi_reflect
// blends with (the blur does not feed back, so it does not widen frame after frame).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D traced;
layout(set = 0, binding = 1) uniform sampler2D fine_pos;     // GI level 0: position, z
layout(set = 0, binding = 2) uniform sampler2D fine_nrm;     // GI level 0: normal
layout(set = 0, binding = 3) uniform sampler2D gb_specular;  // a: lobe kind (0 Lambert)
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D blurred;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2D history;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(blurred);
    if (any(greaterThanEqual(p, size))) return;
    vec4 center = texelFetch(traced, p, 0);
    imageStore(history, p, center);
    float z = texelFetch(fine_pos, p, 0).w;
    if (z <= 0.0 || texelFetch(gb_specular, p, 0).a < 0.5) {
        imageStore(blurred, p, center);
        return;
    }
    vec3 n = texelFetch(fine_nrm, p, 0).xyz;
    vec4 sum = vec4(0.0);
    float w_sum = 0.0;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            ivec2 q = p + ivec2(x, y);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            float zq = texelFetch(fine_pos, q, 0).w;
            if (zq <= 0.0 || texelFetch(gb_specular, q, 0).a < 0.5) continue;
            float wb = float((2 - abs(x)) * (2 - abs(y)));
            float wn = pow(max(dot(n, texelFetch(fine_nrm, q, 0).xyz), 0.0), 8.0);
            float dz = (zq - z) / (0.05 * z + 1e-3);
            float w = wb * wn * exp(-dz * dz);
            sum += w * texelFetch(traced, q, 0);
            w_sum += w;
        }
    }
    imageStore(blurred, p, w_sum > 0.0 ? sum / w_sum : center);
}

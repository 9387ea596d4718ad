#version 450
// Auto exposure (Oetke 2017 §4.4; Reinhard et al. 2002 §3.1): one workgroup reduces the
// frame to its log-average luminance L̄ = exp(mean(ln(δ + L))), δ = 1e-4 (so black pixels stay
// finite), and sets the exposure key / L̄ — at once in the first frame, afterwards adapted in
// log space by the fraction `adaptation` per frame: ln e ← mix(ln e, ln(key / L̄), adaptation).
// The tone-mapping pass multiplies its radiance by this exposure.
layout(local_size_x = 256) in;
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(set = 0, binding = 1, std430) buffer Exposure {
    float exposure;
    float log_average_luminance;
} result;

layout(push_constant) uniform Push {
    float key;
    float adaptation;
    uint first_frame;
} pc;

const float DELTA = 1e-4;
shared float partial[256];

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

void main() {
    uint i0 = gl_LocalInvocationIndex;
    ivec2 size = textureSize(hdr, 0);
    uint n = uint(size.x) * uint(size.y);
    float sum = 0.0;
    for (uint i = i0; i < n; i += 256u) {
        ivec2 p = ivec2(int(i % uint(size.x)), int(i / uint(size.x)));
        sum += log(DELTA + luminance(max(texelFetch(hdr, p, 0).rgb, vec3(0.0))));
    }
    partial[i0] = sum;
    barrier();
    for (uint s = 128u; s > 0u; s >>= 1u) {
        if (i0 < s) partial[i0] += partial[i0 + s];
        barrier();
    }
    if (i0 == 0u) {
        float log_avg = partial[0] / float(n);
        float target_log = log(pc.key) - log_avg;
        float e_log = pc.first_frame != 0u ? target_log : mix(log(result.exposure), target_log, pc.adaptation);
        result.exposure = exp(e_log);
        result.log_average_luminance = log_avg;
    }
}

#version 450
// Tone mapping of linear HDR radiance to sRGB-encoded 8-bit (Thiedemann 2010, tone mapping):
// 0 linear (exposure, clamp), 1 logarithmic, 2 Drago et al. 2003, 3 filmic (ACES fit,
// Narkowicz 2015). Luminance-based operators scale the color by Ld / Lw. The radiance is
// multiplied by the push exposure times the exposure buffer's (1, or auto exposure's key / L̄).
// With `dither`, triangular noise of ±1/255 (the sum of two uniform variables) is added to
// the encoded value before 8-bit quantization: the quantized value's mean is the unquantized
// value, and a gradient shows no bands.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D ldr;
layout(set = 0, binding = 2, std430) readonly buffer Exposure {
    float exposure;
    float log_average_luminance;
} auto_exposure;

layout(push_constant) uniform Push {
    float exposure;
    uint op;
    float white;    // luminance mapped to 1 (logarithmic, Drago)
    float drago_bias;
    uint dither;
} pc;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

// lowbias32 (Wellons 2018): a well-mixed 32-bit integer hash.
uint hash(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Uniform in [0, 1) from pixel p and stream k.
float uniform01(ivec2 p, uint k) {
    return float(hash(uint(p.x) + hash(uint(p.y) + hash(k))) >> 8) / 16777216.0;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(ldr);
    if (any(greaterThanEqual(p, size))) return;
    vec3 c = max(texelFetch(hdr, p, 0).rgb, vec3(0.0)) * (pc.exposure * auto_exposure.exposure);
    float lw = luminance(c);
    float white = max(pc.white, 1e-6);
    if (pc.op == 1u) {
        c *= lw > 0.0 ? (log(1.0 + lw) / log(1.0 + white)) / lw : 0.0;
    } else if (pc.op == 2u) {
        float b = clamp(pc.drago_bias, 0.5, 1.0);
        float ld = log(lw + 1.0) / (log(white + 1.0) / log(10.0) * log(2.0 + 8.0 * pow(lw / white, log(b) / log(0.5))));
        c *= lw > 0.0 ? ld / lw : 0.0;
    } else if (pc.op == 3u) {
        c = clamp(c * (2.51 * c + 0.03) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
    }
    vec3 e = srgb_encode(c);
    if (pc.dither != 0u) {
        e += (uniform01(p, 0u) + uniform01(p, 1u) - 1.0) / 255.0;
    }
    imageStore(ldr, p, vec4(e, 1.0));
}

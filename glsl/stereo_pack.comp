#version 450
// Packs a stereo pair into one image (src/post/stereo_pack.rs): an anaglyph (a 3×3 matrix per
// eye applied in linear RGB, after Dubois 2001), or a spatial packing of the two eyes. The
// eyes are the tone-mapped sRGB-encoded RGBA8 images, both eye_width × eye_height; spatial
// packings copy their texels unchanged.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D left_eye;
layout(set = 0, binding = 1) uniform sampler2D right_eye;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D packed;

layout(push_constant) uniform Push {
    vec4 left_rows[3];   // anaglyph: output channel i = dot(left_rows[i], L) + dot(right_rows[i], R)
    vec4 right_rows[3];
    uint mode;           // StereoMode::shader_id
    uint eye_width;
    uint eye_height;
} pc;

const uint ANAGLYPH = 0u;
const uint SIDE_BY_SIDE = 1u;
const uint SIDE_BY_SIDE_FULL = 2u;
const uint TOP_BOTTOM = 3u;
const uint ROW_INTERLEAVED = 4u;
const uint COLUMN_INTERLEAVED = 5u;
const uint CHECKERBOARD = 6u;

vec3 srgb_decode(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

// Output coordinate `o` of `packed_n` texels that show `n` eye texels: the eye texel whose
// span holds the output texel's centre, in integers ((2o + 1) n / (2 packed_n)).
uint squeeze(uint o, uint packed_n, uint n) {
    return min((2u * o + 1u) * n / (2u * packed_n), n - 1u);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(packed);
    if (any(greaterThanEqual(p, size))) return;
    uint x = uint(p.x), y = uint(p.y);
    uint w = pc.eye_width, h = pc.eye_height;
    // Left eye's share of a halved axis: the first ceil(n / 2) texels.
    uint wl = (w + 1u) / 2u, hl = (h + 1u) / 2u;
    bool use_left = true;
    uvec2 src = uvec2(x, y);
    if (pc.mode == ANAGLYPH) {
        vec3 l = srgb_decode(texelFetch(left_eye, p, 0).rgb);
        vec3 r = srgb_decode(texelFetch(right_eye, p, 0).rgb);
        vec3 c;
        for (int i = 0; i < 3; ++i) {
            c[i] = dot(pc.left_rows[i].xyz, l) + dot(pc.right_rows[i].xyz, r);
        }
        imageStore(packed, p, vec4(srgb_encode(c), 1.0));
        return;
    } else if (pc.mode == SIDE_BY_SIDE) {
        use_left = x < wl;
        src.x = use_left ? squeeze(x, wl, w) : squeeze(x - wl, w - wl, w);
    } else if (pc.mode == SIDE_BY_SIDE_FULL) {
        use_left = x < w;
        src.x = use_left ? x : x - w;
    } else if (pc.mode == TOP_BOTTOM) {
        use_left = y < hl;
        src.y = use_left ? squeeze(y, hl, h) : squeeze(y - hl, h - hl, h);
    } else if (pc.mode == ROW_INTERLEAVED) {
        use_left = y % 2u == 0u;
    } else if (pc.mode == COLUMN_INTERLEAVED) {
        use_left = x % 2u == 0u;
    } else if (pc.mode == CHECKERBOARD) {
        use_left = (x + y) % 2u == 0u;
    }
    ivec2 s = ivec2(src);
    vec4 c = use_left ? texelFetch(left_eye, s, 0) : texelFetch(right_eye, s, 0);
    imageStore(packed, p, vec4(c.rgb, 1.0));
}

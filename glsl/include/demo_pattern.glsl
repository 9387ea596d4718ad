// The demo graph's test pattern; the integration test recomputes it on the CPU
// (src/demo.rs, `expected_pixel`), so any change here must be mirrored there.
#ifndef DEMO_PATTERN_GLSL
#define DEMO_PATTERN_GLSL

vec4 demo_pattern(uvec2 p, uvec2 size) {
    return vec4((vec2(p) + 0.5) / vec2(size), float((p.x ^ p.y) & 255u) / 255.0, 1.0);
}

#endif

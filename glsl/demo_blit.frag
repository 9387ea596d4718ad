#version 450
// Demo pass 2: a graphics pass samples the pattern into a color attachment, rotating the
// channels (r,g,b) -> (b,r,g) so the test can tell the passes apart.
layout(set = 0, binding = 0) uniform sampler2D src;
layout(location = 0) out vec4 color;

void main() {
    vec4 v = texelFetch(src, ivec2(gl_FragCoord.xy), 0);
    color = vec4(v.b, v.r, v.g, v.a);
}

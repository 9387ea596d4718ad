#version 450
// Builds, once per atlas, the list of valid texels (thesis §3.3 step 2: a point list, not a
// draw of every texel with discards): appends the model-space position of every rendered
// texel (w = 1) to a buffer whose first word counts them.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D atlas;
layout(set = 0, binding = 1, std430) buffer Points { uint count; uint pad[3]; vec4 points[]; };

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(xy, textureSize(atlas, 0)))) {
        return;
    }
    vec4 p = texelFetch(atlas, xy, 0);
    if (p.w > 0.0) {
        uint i = atomicAdd(count, 1u);
        points[i] = vec4(p.xyz, 1.0);
    }
}

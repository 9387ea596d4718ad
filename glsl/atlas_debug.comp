#version 450
// The atlas debug view (src/voxel/atlas_view.rs): one object's position atlas, drawn from the
// top-left corner at an integer zoom (or every den-th texel when it is larger than the view).
// Valid texels show their model-space position normalized to the mesh's box as a color,
// invalid texels black, pixels past the atlas dark gray.
// value = (1 valid / 0 invalid, texel x, texel y) inside the atlas, (-1, -1, -1) outside.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D atlas;   // model-space xyz, w = 1 where valid
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D value;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D color;

layout(push_constant) uniform Push {
    uvec4 atlas_zoom;   // atlas width, height (texels); texel = pixel * den / num: num, den
    vec4 box_min;       // the mesh's model-space box
    vec4 box_scale;     // 1 / its extent (0 on flat axes)
} pc;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, imageSize(color)))) {
        return;
    }
    uvec2 texel = uvec2(px) * pc.atlas_zoom.w / pc.atlas_zoom.z;
    vec4 v = vec4(-1.0, -1.0, -1.0, 1.0);
    vec3 c = vec3(0.12);
    if (all(lessThan(texel, pc.atlas_zoom.xy))) {
        vec4 p = texelFetch(atlas, ivec2(texel), 0);
        bool valid = p.w > 0.0;
        v = vec4(valid ? 1.0 : 0.0, vec2(texel), 1.0);
        // Lifted off black so that the box's minimum corner stays apart from invalid texels.
        c = valid ? 0.15 + 0.85 * clamp((p.xyz - pc.box_min.xyz) * pc.box_scale.xyz, 0.0, 1.0)
                  : vec3(0.0);
    }
    imageStore(value, px, v);
    imageStore(color, px, vec4(c, 1.0));
}

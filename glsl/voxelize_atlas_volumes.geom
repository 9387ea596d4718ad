#version 450
// Layered rendering into the volumes (Thiedemann 2010, §4.3.2): the point's depth index is its layer, so
// the fragment lands in the voxel whose bit voxelize_atlas sets. The thesis looks the layer
// up in a 1D LUT so that its quantization matches the bits; here both stages share the
// integer voxel of atlas_voxel.glsl, which is the same guarantee without a LUT.
layout(points) in;
layout(points, max_vertices = 1) out;

layout(location = 0) flat in int v_layer[];
layout(location = 1) flat in vec3 v_albedo[];
layout(location = 2) flat in vec4 v_normal[];
layout(location = 3) flat in vec4 v_emission[];
layout(location = 4) flat in vec4 v_material[];
layout(location = 0) flat out vec3 g_albedo;
layout(location = 1) flat out vec4 g_normal;
layout(location = 2) flat out vec4 g_emission;
layout(location = 3) flat out vec4 g_material;

void main() {
    if (v_layer[0] < 0) {
        return;   // outside the grid: no bit, no attribute
    }
    gl_Position = gl_in[0].gl_Position;
    gl_Layer = v_layer[0];
    g_albedo = v_albedo[0];
    g_normal = v_normal[0];
    g_emission = v_emission[0];
    g_material = v_material[0];
    EmitVertex();
    EndPrimitive();
}

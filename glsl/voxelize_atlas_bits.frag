#version 450
// Writes the single-bit LUT entry of the point's depth (Thiedemann 2010, §4.3.1, Fig. 12); the pipeline's
// logicOp OR merges it into the column.
layout(set = 0, binding = 1, std430) readonly buffer Lut { uvec4 single_bit[128]; };
layout(location = 0) flat in uint g_depth;
layout(location = 0) out uvec4 o_column;

void main() {
    o_column = single_bit[g_depth & 127u];
}

#version 450
// The G-buffer of both stereo eyes in one multiview pass (Vulkan 1.1 multiview).
#extension GL_EXT_multiview : require
#define MULTIVIEW
#include "gbuffer_frag.glsl"

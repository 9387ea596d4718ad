#version 450
#include "gbuffer_frag.glsl"

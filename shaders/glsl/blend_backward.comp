#version 460
// Backward of blend.comp with float atomics (VK_EXT_shader_atomic_float).
#include "blend_backward_main.glsl"

#version 460
// Backward of blend.comp with compare-and-swap accumulation, for devices without float atomics.
#define NO_FLOAT_ATOMICS
#include "blend_backward_main.glsl"

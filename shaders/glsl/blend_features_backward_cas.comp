#version 460
// Feature backward with compare-and-swap accumulation.
#define NO_FLOAT_ATOMICS
#include "blend_features_backward_main.glsl"

#version 460
// Projection backward for the compare-and-swap accumulator layout.
#define NO_FLOAT_ATOMICS
#include "project_backward_main.glsl"

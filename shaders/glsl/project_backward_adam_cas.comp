#version 460
// Projection backward fused with Adam, for the compare-and-swap accumulator layout.
#define NO_FLOAT_ATOMICS
#include "project_backward_adam_main.glsl"

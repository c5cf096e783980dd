#version 460
// Projection backward fused with Adam (gradient accumulators read as floats).
#include "project_backward_adam_main.glsl"

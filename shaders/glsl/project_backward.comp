#version 460
// Projection backward (gradient accumulators read as floats).
#include "project_backward_main.glsl"

#version 460
// Feature backward with float atomics.
#include "blend_features_backward_main.glsl"

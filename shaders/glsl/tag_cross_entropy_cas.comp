#version 460
// tag_cross_entropy with compare-and-swap accumulation.
#define NO_FLOAT_ATOMICS
#include "tag_cross_entropy_main.glsl"

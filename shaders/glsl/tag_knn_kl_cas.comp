#version 460
// tag_knn_kl with compare-and-swap accumulation.
#define NO_FLOAT_ATOMICS
#include "tag_knn_kl_main.glsl"

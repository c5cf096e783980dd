#version 460
// tag_knn_kl with float atomics.
#include "tag_knn_kl_main.glsl"

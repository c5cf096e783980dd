#version 460
// tag_cross_entropy with float atomics.
#include "tag_cross_entropy_main.glsl"

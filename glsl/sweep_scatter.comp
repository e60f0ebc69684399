#version 460
#extension GL_GOOGLE_include_directive : require
// The compute sweep's scatter of ray blocks (sweep_scatter.glsl) with two 32-bit words
// per sum: the low word's old value gives the carry (every device).
#define SPLAT_INT64 0
#include "sweep_scatter.glsl"

#version 460
// The benchmark floor of the compute sweep (sweep_floor.glsl): the same work per pixel in one
// dispatch per plane, with the compute sweep's barriers.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_floor.glsl"

#version 460
// The benchmark skeleton of the compute sweep (sweep_skeleton.glsl): the same work per pixel in one
// dispatch per plane, with the compute sweep's barriers.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_skeleton.glsl"

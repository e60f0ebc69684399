#version 460
// The benchmark skeleton of the fragment sweep (sweep_skeleton.glsl).
#extension GL_GOOGLE_include_directive : require
#include "sweep_skeleton.glsl"

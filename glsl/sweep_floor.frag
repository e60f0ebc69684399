#version 460
// The benchmark floor of the fragment sweep (sweep_floor.glsl).
#extension GL_GOOGLE_include_directive : require
#include "sweep_floor.glsl"

#version 460
// A plane of the sweep with the forward (Lagrangian) light transport, hard light.
#extension GL_GOOGLE_include_directive : require
#define FORWARD_LIGHT 1
#define SOFT_LIGHT 0
#include "sweep_plane.glsl"

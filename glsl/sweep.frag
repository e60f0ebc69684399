#version 460
// A plane of the sweep with the thesis' light transport: the backward (semi-Lagrangian)
// step with the intensity law (eqs. 4.4-4.8), light and viewing rays in one draw.
// `--light-transport backward`.
#extension GL_GOOGLE_include_directive : require
#define FORWARD_LIGHT 0
#define SOFT_LIGHT 0
#define PASS 0
#include "sweep_plane.glsl"

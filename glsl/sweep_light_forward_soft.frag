#version 460
// As sweep_light_forward.frag, with soft light (flux diffusion between neighbouring rays).
// A separate build rather than a runtime branch: llvmpipe runs both sides of a uniform
// branch.
#extension GL_GOOGLE_include_directive : require
#define FORWARD_LIGHT 1
#define SOFT_LIGHT 1
#define PASS 1
#include "sweep_plane.glsl"

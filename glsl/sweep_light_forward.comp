#version 460
// The compute sweep's counterpart of sweep_light_forward.frag (issue 31): the same plane shader
// (sweep_plane.glsl) as one dispatch per plane on storage images.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#define FORWARD_LIGHT 1
#define SOFT_LIGHT 0
#define PASS 1
#include "sweep_plane.glsl"

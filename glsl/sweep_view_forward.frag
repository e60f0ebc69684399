#version 460
// Forward light transport, last draw of a plane: the viewing rays cross the segment from
// the previous plane to this one, lit by the irradiance of both planes.
#extension GL_GOOGLE_include_directive : require
#define FORWARD_LIGHT 1
#define SOFT_LIGHT 0
#define PASS 2
#include "sweep_plane.glsl"

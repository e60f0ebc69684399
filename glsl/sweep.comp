#version 460
// The compute sweep's counterpart of sweep.frag (issue 31): the same plane shader
// (sweep_plane.glsl) as one dispatch per plane on storage images.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#define FORWARD_LIGHT 0
#define SOFT_LIGHT 0
#define PASS 0
#define LIGHT_TILE_READS 1   // the `tile` lever (sweep_plane_io.glsl)
#include "sweep_plane.glsl"

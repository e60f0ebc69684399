#version 460
// Forward light transport, first draw of a plane: the light rays advance to it (hard
// light). light_splat.* then deposits their flux, sweep_view_forward.frag moves the
// viewing rays.
#extension GL_GOOGLE_include_directive : require
#define FORWARD_LIGHT 1
#define SOFT_LIGHT 0
#define PASS 1
#include "sweep_plane.glsl"

#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
// The compute sweep's scatter of ray blocks (sweep_scatter.glsl) with one 64-bit atomic
// per sum, built for the boxes deposit alone (its 3 vec4s a ray: the block's 64 rays
// dealt out at once).
#define SPLAT_INT64 1
#define DEPOSIT_BOXES_ONLY 1
#include "sweep_scatter.glsl"

#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
// The compute sweep's scatter of ray blocks (sweep_scatter.glsl) with one 64-bit atomic
// per sum, on devices with shaderBufferInt64Atomics.
#define SPLAT_INT64 1
#include "sweep_scatter.glsl"

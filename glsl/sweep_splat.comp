#version 460
// The compute sweep's splat (issue 31): light_splat.comp's deposits, with the light rays
// read from the storage images the compute sweep binds (sweep_buffers.glsl).
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "light_splat_main.glsl"

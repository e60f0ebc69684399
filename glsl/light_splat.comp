#version 460
// Forward light transport, second half of a plane (the `splat=compute` lever): one
// invocation per light ray adds its deposit (light_splat_ray.glsl) to the fixed-point sums
// of the pixels its box overlaps (light_splat_fixed.glsl); light_splat_resolve.comp turns
// the sums into the plane's irradiance. Same deposits as the point sprites of
// light_splat.vert/.frag, without rasterising a sprite per ray and blending two RGBA32F
// attachments (84 % of the forward sweep on an H100, 45 % on lavapipe, measured).
#extension GL_GOOGLE_include_directive : require
#include "light_splat_main.glsl"

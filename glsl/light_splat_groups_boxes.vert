#version 460
// The grouped point sprites' vertex shader for the boxes deposit (the `splat=groups` lever):
// light_splat_sprite.glsl.
#extension GL_GOOGLE_include_directive : require
#define SPRITE_VERTEX 1
#define SPRITE_CELLS 0
#define SPRITE_GROUPS 1
#include "light_splat_sprite.glsl"

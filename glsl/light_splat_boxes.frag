#version 460
// The point-sprite splat's fragment shader for the boxes deposit: light_splat_sprite.glsl.
#extension GL_GOOGLE_include_directive : require
#define SPRITE_VERTEX 0
#define SPRITE_CELLS 0
#include "light_splat_sprite.glsl"

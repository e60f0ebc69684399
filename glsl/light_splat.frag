#version 460
// The point-sprite splat's fragment shader for the cells deposit (and boxes, by specialization constant 9): light_splat_sprite.glsl.
#extension GL_GOOGLE_include_directive : require
#define SPRITE_VERTEX 0
#define SPRITE_CELLS 1
#include "light_splat_sprite.glsl"

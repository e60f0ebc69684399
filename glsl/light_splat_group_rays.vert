#version 460
// The grouped sprites' second draw for the boxes deposit (the `splat=groups` lever): one
// point per ray of a group too wide for one sprite, its deposit as light_splat_groups.comp
// stored it, with the three varyings of one box (light_splat_boxes.frag shades it), not
// the group sprite's twelve: light_splat_sprite.glsl.
#extension GL_GOOGLE_include_directive : require
#define SPRITE_VERTEX 1
#define SPRITE_CELLS 0
#define SPRITE_GROUPS 0
#define SPRITE_FROM_LIST 1
#include "light_splat_sprite.glsl"

// The six state buffers of the plane sweep, each a 2-layer image array sampled through
// per-layer views (bindings 4 + 2 * buffer + layer). The read layer comes as a push
// constant; both layers are always valid to the validation layer (GENERAL layout), so
// nothing is rebound between planes.
#ifndef REFRAKT_SWEEP_BUFFERS_GLSL
#define REFRAKT_SWEEP_BUFFERS_GLSL

layout(set = 0, binding = 4) uniform sampler2D light_colour_0;
layout(set = 0, binding = 5) uniform sampler2D light_colour_1;
layout(set = 0, binding = 6) uniform sampler2D light_direction_0;
layout(set = 0, binding = 7) uniform sampler2D light_direction_1;
layout(set = 0, binding = 8) uniform sampler2D view_position_0;
layout(set = 0, binding = 9) uniform sampler2D view_position_1;
layout(set = 0, binding = 10) uniform sampler2D view_direction_0;
layout(set = 0, binding = 11) uniform sampler2D view_direction_1;
layout(set = 0, binding = 12) uniform sampler2D colour_opacity_0;
layout(set = 0, binding = 13) uniform sampler2D colour_opacity_1;
layout(set = 0, binding = 14) uniform sampler2D medium_0;
layout(set = 0, binding = 15) uniform sampler2D medium_1;

#define READ_BUFFER(name, layer, uv) \
    ((layer) == 0u ? textureLod(name##_0, (uv), 0.0) : textureLod(name##_1, (uv), 0.0))

#endif

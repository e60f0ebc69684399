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

// Bilinear interpolation with full f32 weights. Hardware filtering quantises the weights
// (8 sub-texel bits on lavapipe, 8 on most GPUs): the light moves a small fraction of a
// texel per plane, and that rounding, repeated every plane, shifted a ball lens' focus by
// more than 10 % (measured). Clamp-to-edge addressing.
vec4 bilinear(sampler2D tex, vec2 uv) {
    ivec2 size = textureSize(tex, 0);
    vec2 x = uv * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 t = x - vec2(i);
    ivec2 hi = size - 1;
    vec4 a = texelFetch(tex, clamp(i, ivec2(0), hi), 0);
    vec4 b = texelFetch(tex, clamp(i + ivec2(1, 0), ivec2(0), hi), 0);
    vec4 c = texelFetch(tex, clamp(i + ivec2(0, 1), ivec2(0), hi), 0);
    vec4 d = texelFetch(tex, clamp(i + ivec2(1, 1), ivec2(0), hi), 0);
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}

// A state value at an arbitrary position (bilinear) of the read layer.
#define READ_BUFFER(name, layer, uv) \
    ((layer) == 0u ? bilinear(name##_0, (uv)) : bilinear(name##_1, (uv)))

// A state value of this pixel of the read layer (exact, one fetch).
#define READ_PIXEL(name, layer, pixel) \
    ((layer) == 0u ? texelFetch(name##_0, (pixel), 0) : texelFetch(name##_1, (pixel), 0))

#endif

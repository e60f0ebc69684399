// What the plane passes share beyond the state buffers: the irradiance of the current
// plane splatted from the forward transport's light rays, and the clamp counters.
#ifndef REFRAKT_SWEEP_LIGHT_GLSL
#define REFRAKT_SWEEP_LIGHT_GLSL

// Irradiance of the last two planes, ping-ponged like the state (plane i in layer i % 2):
// rgb = flux per unit plane area, relative to the unobstructed light (an unobstructed
// beam reads the light colour), a unused.
layout(set = 0, binding = 16) uniform sampler2D irradiance_0;
layout(set = 0, binding = 17) uniform sampler2D irradiance_1;
// xyz = sum of luminance-weighted unit light directions, w = sum of the weights.
layout(set = 0, binding = 18) uniform sampler2D irradiance_direction_0;
layout(set = 0, binding = 19) uniform sampler2D irradiance_direction_1;

// How often the sweep had to bend physics, summed over pixels and planes (read back and
// printed): 0 = light direction clamped to MIN_FORWARD, 1 = light ray turned back and
// dropped, 2 = viewing-ray direction clamped, 3 = backward step's intensity gain clamped.
layout(set = 0, binding = 20, std430) buffer Counters {
    uint clamps[4];
} counters;

// The environment map for Fresnel reflections of viewing rays (a 2 x 1 black map when
// there is none; SweepParams.refraction.z says whether to use it).
layout(set = 0, binding = 25) uniform sampler2D reflection_env;

void count_clamp(uint which) {
    atomicAdd(counters.clamps[which], 1u);
}

#endif

// What the plane passes share beyond the state buffers: the irradiance of the current
// plane splatted from the forward transport's light rays, and the clamp counters.
#ifndef REFRAKT_SWEEP_LIGHT_GLSL
#define REFRAKT_SWEEP_LIGHT_GLSL

// Irradiance of the last two planes, ping-ponged like the state (plane i in layer i % 2):
// rgb = flux per unit plane area, relative to the unobstructed light (an unobstructed
// beam reads the light colour), a unused.
STATE_IMAGE(10, irradiance);
// xyz = sum of luminance-weighted unit light directions, w = sum of the weights.
STATE_IMAGE(11, irradiance_direction);
DEFINE_BILINEAR(irradiance)
DEFINE_BILINEAR(irradiance_direction)

// How often the sweep had to bend physics, summed over pixels and planes (read back and
// printed): 0 = light direction clamped to MIN_FORWARD, 1 = light ray turned back and
// dropped, 2 = viewing-ray direction clamped, 3 = backward step's intensity gain clamped.
layout(set = 0, binding = 12, std430) buffer Counters {
    uint clamps[4];
} counters;

// The environment map for Fresnel reflections of viewing rays (a 2 x 1 black map when
// there is none; SweepParams.refraction.z says whether to use it).
layout(set = 0, binding = 15) uniform sampler2D reflection_env;

// The smoothed gradient of the value (render::gradient: a derivative-of-Gaussian filter,
// sigma 1.5 voxels, built once per volume): xyz in value units per voxel, w the smoothed
// value. Specialization constant 0 says whether it is bound (when it would not fit in
// memory, the volume stands in for it and is never read through this binding).
layout(constant_id = 0) const bool HAVE_GRADIENT_VOLUME = true;
layout(set = 0, binding = 16) uniform sampler3D gradient_volume;

// Direction of a surface at view-space p, view-space units, zero outside the volume box.
// With the gradient volume: one trilinear fetch, within ~0.1° of a face's normal not
// aligned with the grid (median; 0.5° at the 95th percentile) where the thesis' central
// differences one voxel apart, and the fallback below, tilt it by 1-3° (measured on a
// voxelised sphere, render/gradient.rs). Without: a 3D Sobel of trilinear fetches one
// voxel apart (26 fetches).
vec3 surface_gradient_tex(vec3 t) {
    vec3 g = vec3(0.0);
    if (HAVE_GRADIENT_VOLUME) {
        g = textureLod(gradient_volume, t, 0.0).xyz * P.volume_dims.xyz;
    } else {
        vec3 h = 1.0 / P.volume_dims.xyz;
        for (int k = 0; k < 27; ++k) {
            ivec3 o = ivec3(k % 3, (k / 3) % 3, k / 9) - 1;
            if (o == ivec3(0)) continue;
            // Weight 2 across each difference where the other offsets are 0 (1-2-1).
            vec3 w = vec3(o.x == 0 ? 2.0 : 1.0, o.y == 0 ? 2.0 : 1.0, o.z == 0 ? 2.0 : 1.0);
            g += value_at_tex(t + vec3(o) * h)
               * vec3(o) * vec3(w.y * w.z, w.x * w.z, w.x * w.y);
        }
        // Sobel weights sum to 16 per side; / (2 h) for a central difference.
        g /= 32.0 * h;
    }
    return transpose(mat3(P.view_to_tex)) * g;
}

vec3 surface_gradient(vec3 p) {
    vec3 t = to_tex(p);
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return vec3(0.0);
    return surface_gradient_tex(t);
}

// The light's direction from the forward splat's luminance-weighted direction sum (w: the
// weight): the launch direction where no light arrived. The sum's channels are rounded
// apart (32.32 fixed point on the compute paths), so a weight can survive where the
// direction rounded to zero: normalising that gave NaN pixels (measured, with the cells
// deposit's many small shares).
vec3 splatted_direction(vec4 sum) {
    return sum.w > 0.0 && dot(sum.xyz, sum.xyz) > 0.0 ? normalize(sum.xyz)
                                                      : normalize(P.light_dir.xyz);
}

// The eikonal light transport (`--light-transport eikonal`, issue 35 item 5): the light
// simulated beforehand as adaptive wavefronts into a light volume (render/eikonal, the
// eikonal model's light), read here instead of propagated plane by plane, so the light
// may come from any direction and need not keep pace with the sweep. Specialization
// constant 10; the binding holds a placeholder for the other transports.
layout(constant_id = 10) const bool LIGHT_FROM_VOLUME = false;
layout(std430, set = 0, binding = 26) readonly buffer LightVolume {
    vec4 light_volume[];
};
#define LIGHT_VOLUME light_volume
#include "light_volume.glsl"

// The light at view-space point p from the light volume: its fluence (the light's units:
// an unobstructed beam reads the light colour, as the planes' light does) and the
// direction it travels in view space (its luminance-weighted mean, normalised; the
// main light's where none arrives).
void volume_light(vec3 p, out vec3 light, out vec3 dir) {
    vec3 d_world;
    light_volume_at(to_tex(p), P.volume_dims.xyz, light, d_world);
    // view_to_world is a rotation (and the eye's translation): its transpose turns back.
    vec3 d = transpose(mat3(P.view_to_world)) * d_world;
    dir = dot(d, d) > 1e-12 ? normalize(d) : normalize(P.light_dir.xyz);
}

void count_clamp(uint which) {
    atomicAdd(counters.clamps[which], 1u);
}

#endif

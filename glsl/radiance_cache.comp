#version 460
// The ambient-scattering model's radiance cache (render/ambient; Ament et al. sect.
// 3.2.2 and 4.2.2, eqs. 14-17): for every cache voxel (half the volume's resolution per
// axis, as the paper's) and every light, the light front L_d that reaches the voxel's
// centre through "shadow-and-scatter tubes" of radius r, one channel per light.
//
// Tube marching: from where the light enters the box (or from a point light inside it),
// the front steps towards the voxel by 2r, each step crossing one ambient sphere, and is
// multiplied per step by the sphere's transmission t(r * ambient extinction, g): the
// irradiance a unit collimated front leaves at the sphere's far pole, direct and scattered
// (table.rs). The paper multiplies by its radial table entry at theta = 0 instead
// (eq. 16), which in empty space is p_HG(0; g) / (4 pi), not 1, per step; t is 1 in empty
// space, e^(-2s) without scattering, and never above 1. The sphere a step crosses is the
// one centred between its ends (the paper samples at the step's start).
//
// The paper marches from the light in a grid of steps fixed at the light and interpolates
// the two fronts around the voxel (eq. 17). At a sharp interface that modulates the light
// with period 2r: a voxel just under a lit surface gets the front from a step that ends
// above the surface or one that crossed a whole sphere straddling it, depending on where
// the grid falls (measured: stripes across a lit floor). Here each voxel lays its own
// steps, from itself towards the light, so the last sphere always ends at the voxel and
// the partial step lies at the far end, where the light enters the box.
// A point light's front also falls off as 1 / distance^2 (its colour is the irradiance at
// unit distance).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler3D ambient_extinction;
// [s, g]: the scattered part of the transmission; the direct e^(-2s) is added here, exact.
layout(set = 0, binding = 1) uniform sampler2D transmission;
layout(set = 0, binding = 2, rgba32f) uniform writeonly image3D radiance;

layout(push_constant) uniform Push {
    vec4 lights[MAX_LIGHTS];    // xyz: direction towards the light (unit) or position; w: 0 / 1 = point
    vec4 half_extent;  // xyz: the box's half extent (world), w: r (world)
    vec4 table;        // n_theta, n_s, n_g, s_max
    vec4 misc;         // x: g, y: r in reference steps, z: number of lights
} pc;

#define AMBIENT_TABLE_DIMS pc.table
#include "ambient_table.glsl"

float sphere_transmission(vec3 centre) {
    vec3 h = pc.half_extent.xyz;
    // Outside the box the medium is empty.
    float sigma = any(greaterThan(abs(centre), h)) ? 0.0
        : texture(ambient_extinction, centre / (2.0 * h) + 0.5).r;
    float s = pc.misc.y * sigma;
    vec2 tc = vec2(ambient_s_coord(s), ambient_g_coord(pc.misc.x));
    return exp(-2.0 * s) + texture(transmission, tc).r;
}

void main() {
    ivec3 dims = imageSize(radiance);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, dims))) return;
    vec3 h = pc.half_extent.xyz;
    float r = pc.half_extent.w;
    vec3 x = ((vec3(v) + 0.5) / vec3(dims) - 0.5) * 2.0 * h;
    vec4 front = vec4(0.0);
    int n = int(pc.misc.z);
    for (int j = 0; j < n; ++j) {
        vec4 l = pc.lights[j];
        vec3 u = l.xyz;  // towards the light
        float falloff = 1.0;
        float reach;     // from x along u to where the light starts
        vec3 inv;
        if (l.w > 0.5) {
            vec3 to = l.xyz - x;
            float dist = max(length(to), 1e-6);
            u = to / dist;
            falloff = 1.0 / (dist * dist);
            inv = 1.0 / u;
            vec3 t1 = max((h - x) * inv, (-h - x) * inv);
            reach = min(max(min(min(t1.x, t1.y), t1.z), 0.0), dist);
        } else {
            inv = 1.0 / u;
            vec3 t1 = max((h - x) * inv, (-h - x) * inv);
            reach = max(min(min(t1.x, t1.y), t1.z), 0.0);
        }
        // The tube's spheres are laid from the voxel towards the light, so the last one
        // ends at the voxel: the partial step is at the far end, where the light enters.
        float steps = reach / (2.0 * r);
        int k = int(floor(steps));
        float eta = steps - float(k);
        float f = 1.0;
        for (int i = 0; i < k; ++i) {
            f *= sphere_transmission(x + (float(i) + 0.5) * 2.0 * r * u);
        }
        // The partial step: the fraction eta of a sphere's transmission, geometrically
        // (exact without scattering: e^(-2 s eta)).
        if (eta > 0.0) {
            f *= pow(sphere_transmission(x + (float(k) + 0.5 * eta) * 2.0 * r * u), eta);
        }
        front[j] = falloff * f;
    }
    imageStore(radiance, v, front);
}

#version 460
// Single scattering with shadows (`--model single`; render/single): the emission-absorption
// march of ea.comp (march.glsl) in which a segment's colour is the medium's scattering
// colour (the transfer function's colour times the albedo) lit by the directional light
// that reaches it (the transmittance cache) and scattered towards the eye by the
// Henyey-Greenstein phase function:
//
//   shade(x, dir) = light colour * albedo * T(x) * 4 pi p_HG(cos theta; g),
//   cos theta = towards . dir   (the angle between the light's travel, -towards, and the
//                                scattered light's, -dir),
//
// normalised so that isotropic scattering (g = 0) gives 4 pi p = 1: with T = 1 and albedo
// 1 the image is EA's. Regions the light does not reach are black: there is no ambient
// term (the AO and ambient-scattering models have one).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "raycast.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform Params {
    vec4 cam_pos;
    vec4 cam_forward;
    vec4 cam_right;
    vec4 cam_up;
    vec4 box_half;
    vec4 background;
    vec4 march;
    uvec4 size;
    // As ea.comp up to here.
    vec4 light;        // xyz = unit direction towards the light (world), w = g
    vec4 light_colour; // rgb, linear; w = albedo
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;
layout(set = 0, binding = 5) uniform sampler3D transmittance;

#include "phase.glsl"

vec3 sample_shade(vec3 p, vec3 dir) {
    float t = texture(transmittance, p / (2.0 * P.box_half.xyz) + 0.5).r;
    float phase = hg4pi(dot(P.light.xyz, dir), P.light.w);
    return P.light_colour.rgb * (P.light_colour.w * t * phase);
}
#include "march.glsl"

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz, P.cam_up.xyz);
    imageStore(frame, ivec2(id), march_ray(P.cam_pos.xyz, dir));
}

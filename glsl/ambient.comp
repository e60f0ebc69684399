#version 460
// Ambient scattering (`--model ambient`; render/ambient): Ament et al.'s ambient ray
// casting (sect. 4.2.3, eqs. 18-21, Algorithm 1) on the emission-absorption march of
// ea.comp (march.glsl). A segment's colour is the medium's scattering colour (the transfer
// function's colour times the albedo) lit, per light j, by the light front L_d,j that the
// radiance cache holds where the light enters the ambient sphere around the sample,
// x_j = x - r w_j (w_j the light's direction of travel), times the light the sphere sends
// towards the eye per unit front (eq. 21):
//
//   shade(x, dir) = albedo * sum_j colour_j * L_d,j(x_j) * (e^(-s) 4 pi p_HG(cos theta_j; g)
//                                                           + S(theta_j, s, g)),
//   s = r * ambient extinction(x),  cos theta_j = w_j . (-dir),
//
// the first term the front scattered once at the sample after crossing the sphere's radius
// (analytic), S the light scattered more than once inside the sphere (the Monte-Carlo
// table, table.rs). Both are radiance at the sphere's centre, so the march's own
// transmittance from the sample to the eye applies unchanged (the paper's table is the
// radiance at the sphere's surface and its Algorithm 1 offsets the transmittance by r
// instead). With r -> 0, S -> 0 and the tube's transmission -> e^(-2s): single scattering
// (single.comp), which is the same normalisation: g = 0, albedo 1, unshadowed gives EA.
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
    vec4 lights[MAX_LIGHTS];   // xyz: direction towards the light (unit) or position; w: 0 / 1 = point
    vec4 colours[MAX_LIGHTS];  // rgb, linear (a point light's: irradiance at unit distance)
    vec4 ambient;     // x: r (world), y: r (reference steps), z: g, w: albedo
    vec4 table;       // n_theta, n_s, n_g, s_max
    uvec4 counts;     // x: number of lights
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;
layout(set = 0, binding = 5) uniform sampler3D ambient_extinction;
layout(set = 0, binding = 6) uniform sampler3D radiance;
layout(set = 0, binding = 7) uniform sampler3D scattered;  // [theta, s, g]

#define AMBIENT_TABLE_DIMS P.table
#include "ambient_table.glsl"

vec3 sample_shade(vec3 p, vec3 dir) {
    vec3 h = P.box_half.xyz;
    float s = P.ambient.y * texture(ambient_extinction, p / (2.0 * h) + 0.5).r;
    float g = P.ambient.z;
    float direct = exp(-s);
    vec2 sg = vec2(ambient_s_coord(s), ambient_g_coord(g));
    vec3 light = vec3(0.0);
    for (uint j = 0u; j < P.counts.x; ++j) {
        vec4 l = P.lights[j];
        vec3 w = l.w > 0.5 ? normalize(p - l.xyz) : -l.xyz;
        vec3 xj = p - P.ambient.x * w;
        float front = texture(radiance, xj / (2.0 * h) + 0.5)[j];
        float c = dot(w, -dir);
        float table = texture(scattered, vec3(ambient_theta_coord(c), sg)).r;
        light += P.colours[j].rgb * (front * (direct * hg4pi(c, g) + table));
    }
    return P.ambient.w * light;
}
#include "march.glsl"

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz, P.cam_up.xyz);
    imageStore(frame, ivec2(id), march_ray(P.cam_pos.xyz, dir));
}

#version 460
// Baseline emission-absorption ray marcher (thesis sect. 3.4-3.7, 3.9): the shared march
// (march.glsl) with unlit emission.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "raycast.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform Params {
    vec4 cam_pos;      // xyz eye, w = tan(fov_y / 2)
    vec4 cam_forward;  // xyz, w = aspect (width / height)
    vec4 cam_right;
    vec4 cam_up;
    vec4 box_half;     // xyz half extent of the volume box, w = reference step (world units)
    vec4 background;   // linear RGBA composited behind the volume
    vec4 march;        // x = sample distance (reference steps), y = termination alpha,
                       // z = 1 for preintegrated segments, w = unused
    uvec4 size;        // x, y = image size
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;

vec3 sample_shade(vec3 p, vec3 dir) { return vec3(1.0); }
#include "march.glsl"

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz, P.cam_up.xyz);
    imageStore(frame, ivec2(id), march_ray(P.cam_pos.xyz, dir));
}

#version 460
// Volumetric ambient occlusion (`--model ao`; render/ao): the emission-absorption march of
// ea.comp with each segment's emission lit by the ambient light that reaches it (ao.glsl:
// transmittance over nested cubes of the extinction volume's summed-area table, cached per
// voxel by ao_cache.comp and interpolated trilinearly) and,
// weighted by `diffuse`, by a directional light through the gradient's normal:
//
//   shade(x) = light colour * AO(x) * ((1 - diffuse) + diffuse * |n(x) . l|),
//
// two-sided (a volume's gradient has no outside), with n the normalised gradient of the
// value by central differences; where the gradient vanishes (inside a homogeneous
// region) there is no surface to light and the diffuse factor is 1. The light is not
// shadowed: that is the single-scattering model's job.
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
    vec4 light;        // xyz = unit direction towards the light (world), w = diffuse weight
    vec4 light_colour; // rgb, linear
    ivec4 dims;        // xyz = volume size in voxels
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;
layout(set = 0, binding = 5) uniform sampler3D occlusion;   // ao_cache.comp

vec3 to_tex(vec3 p) { return p / (2.0 * P.box_half.xyz) + 0.5; }

vec3 sample_shade(vec3 p, vec3 dir) {
    vec3 tex = to_tex(p);
    float ao = texture(occlusion, tex).r;
    vec3 h = 1.0 / vec3(P.dims.xyz);
    vec3 g = vec3(
        texture(volume, tex + vec3(h.x, 0, 0)).r - texture(volume, tex - vec3(h.x, 0, 0)).r,
        texture(volume, tex + vec3(0, h.y, 0)).r - texture(volume, tex - vec3(0, h.y, 0)).r,
        texture(volume, tex + vec3(0, 0, h.z)).r - texture(volume, tex - vec3(0, 0, h.z)).r);
    // A change of the value below 1e-4 across two voxels is no surface.
    float lambert = dot(g, g) > 1e-8 ? abs(dot(normalize(g), P.light.xyz)) : 1.0;
    return P.light_colour.rgb * (ao * ((1.0 - P.light.w) + P.light.w * lambert));
}
#include "march.glsl"

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz, P.cam_up.xyz);
    vec4 c = march_ray(P.cam_pos.xyz, dir);
    imageStore(frame, ivec2(id), c);
}

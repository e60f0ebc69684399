#version 460
// The compute splat's sums (light_splat.comp) become the plane's irradiance and light
// direction (the layer the view pass reads), and are zeroed for the next plane.
#extension GL_GOOGLE_include_directive : require
#define SPLAT_SUMS_BINDING 0
#include "light_splat_fixed.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 1, rgba32f) uniform writeonly image2DArray irradiance;
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2DArray irradiance_direction;

layout(push_constant) uniform Push {
    uint layer;    // the irradiance layer of this plane
    uint width;
    uint height;
    float unit;    // the sums' unit (light_splat.comp)
} pc;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) return;
    vec3 e;
    vec4 dir;
    take_sums(p.y * pc.width + p.x, pc.width * pc.height, pc.unit, e, dir);
    ivec3 at = ivec3(p, pc.layer);
    imageStore(irradiance, at, vec4(e, 0.0));
    imageStore(irradiance_direction, at, dir);
}

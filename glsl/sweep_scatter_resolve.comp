#version 460
// The compute sweep's splat by ray blocks (`gather=blocks`), second of its two
// dispatches: the plane's sums (sweep_scatter.comp, binding 18) become its irradiance and
// light direction (layer `read_layer`, as the gathers store them) and are zeroed for the
// next plane.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_light.glsl"
#define SPLAT_SUMS_BINDING 18
#include "light_splat_fixed.glsl"

// Rows of 64 pixels: each warp reads and zeroes 256 contiguous bytes of each channel's
// sums (8 x 8 workgroups read 64-byte pieces).
layout(local_size_x = 64, local_size_y = 1) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;
    float unit;
} pc;

void main() {
    ivec2 size = ivec2(P.camera.zw);
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, size))) return;
    vec3 e;
    vec4 dir;
    take_sums(uint(p.y * size.x + p.x), uint(size.x * size.y), pc.unit, e, dir);
    ivec3 at = ivec3(p, pc.read_layer);
    imageStore(irradiance, at, vec4(e, 0.0));
    imageStore(irradiance_direction, at, dir);
}

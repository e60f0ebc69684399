#version 460
// The compute sweep's resolve (issue 31): light_splat_resolve.comp on the compute sweep's
// descriptor set, so that the set stays bound across every dispatch of a frame (the
// irradiance images are storage images there, bindings 10 and 11; the sums binding 18).
// The sums become the plane's irradiance and light direction in layer `read_layer` (the
// layer the plane's rays were written to) and are zeroed for the next plane.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_light.glsl"
#define SPLAT_SUMS_BINDING 18
#include "light_splat_fixed.glsl"
#include "sweep_plane_io.glsl"

void plane_main() {
    uvec2 size = uvec2(P.camera.zw);
    uvec2 p = uvec2(g_pixel);
    uint pixels = size.x * size.y;
    uint pixel = p.y * size.x + p.x;
    float c[SPLAT_CHANNELS];
    for (uint k = 0u; k < SPLAT_CHANNELS; ++k) {
        uint slot = splat_slot(k, pixel, pixels);
        c[k] = read_fixed(slot) * pc.unit;
        sums[slot] = 0u;
        sums[slot + 1u] = 0u;
    }
    ivec3 at = ivec3(p, pc.read_layer);
    imageStore(irradiance, at, vec4(c[0], c[1], c[2], 0.0));
    imageStore(irradiance_direction, at, vec4(c[3], c[4], c[5], c[6]));
}

void main() {
    ivec2 gid = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(gid, pc.extent))) return;
    g_pixel = pc.origin + gid;
    plane_main();
}

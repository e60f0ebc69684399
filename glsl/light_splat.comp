#version 460
// Forward light transport, second half of a plane (the `splat=compute` lever): one
// invocation per light ray adds its deposit (light_splat_ray.glsl) to the fixed-point sums
// of the pixels its deposit overlaps (light_splat_fixed.glsl); light_splat_resolve.comp turns
// the sums into the plane's irradiance. Same deposits as the point sprites
// (light_splat_sprite.glsl), without rasterising a sprite per ray and blending two RGBA32F
// attachments (what that cost: docs/NOTES.md, "The sweep as compute").
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#define SPLAT_SUMS_BINDING 18
#include "light_splat_fixed.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    float unit;        // the light's brightest channel: the sums' unit
} pc;

void main() {
    int index = int(gl_GlobalInvocationID.x);
    if (index >= int(P.light_rays.x) * int(P.light_rays.y)) return;
    RayDeposit d;
    if (!ray_deposit(index, pc.read_layer, pc.depth, d)) return;
    ivec2 size = ivec2(P.camera.zw);
    uint pixels = uint(size.x * size.y);
    // Pixels outside the viewport receive nothing (as sprites are clipped there).
    ivec2 first = max(ivec2(floor(d.footprint.xy)), ivec2(0));
    ivec2 last = min(ivec2(floor(d.footprint.zw)), size - 1);
    for (int y = first.y; y <= last.y; ++y) {
        for (int x = first.x; x <= last.x; ++x) {
            vec3 e;
            vec4 dir;
            deposit_at(d, vec2(x, y), pc.unit, e, dir);
            if (!(dir.w > 0.0) && !(max(e.r, max(e.g, e.b)) > 0.0)) continue;
            uint p = uint(y * size.x + x);
            add_fixed(splat_slot(0u, p, pixels), e.r);
            add_fixed(splat_slot(1u, p, pixels), e.g);
            add_fixed(splat_slot(2u, p, pixels), e.b);
            add_fixed(splat_slot(3u, p, pixels), dir.x);
            add_fixed(splat_slot(4u, p, pixels), dir.y);
            add_fixed(splat_slot(5u, p, pixels), dir.z);
            add_fixed(splat_slot(6u, p, pixels), dir.w);
        }
    }
}

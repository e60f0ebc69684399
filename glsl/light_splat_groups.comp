#version 460
// The `splat=groups` lever's pass before each plane's sprites (light_splat_groups.glsl):
// every ray's deposit, each group's footprint, and the indirect draws of the rays of the
// groups that do not fit one sprite. One invocation per group of 2 x 2 rays.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"
#include "light_splat_groups.glsl"

layout(local_size_x = SPLAT_GROUP_WORKGROUP) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    uint pad;          // the first workgroup this plane deposits (render/refract/ray_rows.rs)
} pc;

// What each group of the workgroup is listed as: 0 not at all, 1 one sprite, 2 its rays.
shared uint listed[SPLAT_GROUP_WORKGROUP];

// Whether a footprint (lo.xy, hi.xy, pixels) overlaps the image: one that does not
// deposits on no pixel, so its group is not drawn (a point's vertex costs llvmpipe about
// as much as its fragments; most of the rays lie off the image, docs/NOTES.md).
bool on_image(vec2 lo, vec2 hi) {
    return all(greaterThan(hi, vec2(0.0))) && all(lessThan(lo, P.camera.zw));
}

void main() {
    uint workgroup = gl_WorkGroupID.x + pc.pad;
    int g = int(workgroup * SPLAT_GROUP_WORKGROUP + gl_LocalInvocationID.x);
    uint list = 0u;
    if (g < group_count()) {
        vec2 lo = vec2(1e30), hi = vec2(-1e30);
        bool any_deposit = false;
        for (int k = 0; k < 4; ++k) {
            ivec2 c = group_ray(g, k);
            if (!ray_exists(c)) continue;
            int r = ray_index(c);
            RayDeposit d;
            if (!ray_deposit(r, pc.read_layer, pc.depth, d)) clear_deposit(d);
            store_deposit(r, d);
            if (deposits_anything(d.footprint)) {
                lo = min(lo, d.footprint.xy);
                hi = max(hi, d.footprint.zw);
                any_deposit = true;
            }
        }
        vec2 w = hi - lo;
        bool fits = any_deposit && max(w.x, w.y) <= float(SPLAT_GROUP_SPAN);
        sprite_groups[g] = fits ? vec4(lo, hi) : vec4(0.0);
        bool seen = any_deposit && on_image(lo, hi);
        list = !seen ? 0u : (fits ? 1u : 2u);
    }
    uint t = gl_LocalInvocationID.x;
    listed[t] = list;
    barrier();
    if (t == 0u) {
        // In the groups' order, so the frame does not depend on which invocation ran
        // first: the groups drawn as one sprite from the workgroup's first slot on, then
        // the groups whose rays are drawn one by one.
        uint first = workgroup * SPLAT_GROUP_WORKGROUP;
        uint sprites = 0u;
        for (uint k = 0u; k < SPLAT_GROUP_WORKGROUP; ++k) {
            if (listed[k] == 1u) {
                sprite_fallback[first + sprites] = first + k;
                sprites += 1u;
            }
        }
        uint rays = 0u;
        for (uint k = 0u; k < SPLAT_GROUP_WORKGROUP; ++k) {
            if (listed[k] == 2u) {
                sprite_fallback[first + sprites + rays] = first + k;
                rays += 1u;
            }
        }
        uint workgroups =
            (uint(group_count()) + SPLAT_GROUP_WORKGROUP - 1u) / SPLAT_GROUP_WORKGROUP;
        sprite_draws[workgroup] = uvec4(4u * rays, 1u, 4u * (first + sprites), 0u);
        sprite_draws[workgroups + workgroup] = uvec4(sprites, 1u, first, 0u);
    }
}

#version 460
// The compute sweep's splat, first of its dispatches (light_gather.glsl): each light
// ray's deposit on this plane, and its count in the bins of the screen tiles its deposit
// overlaps. One invocation per ray; the counts are added once per bin and workgroup
// (slot_add).
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    float unit;
    ivec2 origin;      // y: the first grid row this plane deposits (the `rays` lever)
    ivec2 extent;      // y: how many
    uint pad;
} pc;

void main() {
    slots_clear();
    barrier();
    ivec2 ij = DEPOSITED_RAY;
    if (DEPOSITS_HERE(ij)) {
        int r = ray_index(ij);
        RayDeposit d;
        if (!ray_deposit(r, pc.read_layer, pc.depth, d)) {
            clear_deposit(d);   // no deposit: an empty footprint, in no bin
        }
        store_deposit(r, d);
        ivec4 range;
        int level = footprint_bins(d.footprint, range);
        if (level != BIN_NONE) {
            for (int y = range.y; y <= range.w; ++y) {
                for (int x = range.x; x <= range.z; ++x) {
                    uint b = bin_of(level, ivec2(x, y));
                    uint rank;
                    if (slot_add(b, rank) < 0) atomicAdd(bins[b], 1u);
                }
            }
        }
    }
    barrier();
    // One atomic per bin the workgroup's rays fell into.
    uint key = slot_bin[gl_LocalInvocationIndex];
    if (key != 0u) atomicAdd(bins[key - 1u], slot_count[gl_LocalInvocationIndex]);
}

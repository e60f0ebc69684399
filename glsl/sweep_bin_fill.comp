#version 460
// The compute sweep's splat, third of its dispatches (light_gather.glsl): each light ray
// lists itself in the bins sweep_deposit.comp counted it in, at its bin's offset plus a
// cursor, claimed once per bin and workgroup (slot_add). The order within a bin varies
// from run to run; the gather's integer sums do not depend on it.
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
    uint read_layer;
    float depth;
    float unit;
    ivec2 origin;      // y: the first grid row this plane deposits (the `rays` lever)
    ivec2 extent;      // y: how many
    uint pad;
} pc;

void main() {
    slots_clear();
    barrier();
    ivec2 ij = DEPOSITED_RAY;
    uint n = bin_count();
    int r = DEPOSITS_HERE(ij) ? ray_index(ij) : -1;
    ivec4 range = ivec4(0);
    int level = r >= 0 ? footprint_bins(stored_footprint(r), range) : BIN_NONE;
    // Up to MAX_ENTRIES entries (a footprint spans at most GATHER_FINE_SPAN fine or 2
    // coarse tiles a side): the bin, and its slot and rank, or slot -1 for an entry listed
    // at once through its own atomic.
    const int SPAN = max(int(GATHER_FINE_SPAN), 2);
    const int MAX_ENTRIES = SPAN * SPAN;
    uint entry_bin[MAX_ENTRIES];
    int entry_slot[MAX_ENTRIES];
    uint entry_rank[MAX_ENTRIES];
    for (int k = 0; k < MAX_ENTRIES; ++k) {
        ivec2 at = range.xy + ivec2(k % SPAN, k / SPAN);
        bool listed = level != BIN_NONE && all(lessThanEqual(at, range.zw));
        entry_bin[k] = listed ? bin_of(level, at) : 0u;
        entry_slot[k] = -2;   // not listed
        entry_rank[k] = 0u;
        if (listed) {
            entry_slot[k] = slot_add(entry_bin[k], entry_rank[k]);
            if (entry_slot[k] < 0) {
                uint b = entry_bin[k];
                bin_list[bins[n + b] + atomicAdd(bins[2u * n + b], 1u)] = uint(r);
            }
        }
    }
    barrier();
    // Each bin's place for the workgroup's entries: one atomic per bin.
    uint t = gl_LocalInvocationIndex;
    uint key = slot_bin[t];
    if (key != 0u) slot_base[t] = atomicAdd(bins[2u * n + key - 1u], slot_count[t]);
    barrier();
    for (int k = 0; k < MAX_ENTRIES; ++k) {
        if (entry_slot[k] >= 0) {
            uint b = entry_bin[k];
            bin_list[bins[n + b] + slot_base[entry_slot[k]] + entry_rank[k]] = uint(r);
        }
    }
}

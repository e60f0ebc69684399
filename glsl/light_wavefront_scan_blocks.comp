#version 460
// The light simulator's compaction and expansion, first pass (seed 001 sect. 5.2.3, where
// the paper builds a HistoPyramid; here a prefix sum, which Vulkan's compute shaders do
// directly): each block of WAVEFRONT_GROUP patches turns its counts (0, 1 or ku kv, from
// light_wavefront_step.comp) into exclusive offsets within the block, and writes its
// total for light_wavefront_scan_sums.comp.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "light_wavefront.glsl"

shared uint scan[WAVEFRONT_GROUP];

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint l = gl_LocalInvocationID.x;
    uint count = control[CTRL_COUNT + pc.parity];
    uint own = i < count ? counts[i] : 0u;
    scan[l] = own;
    barrier();
    // Hillis-Steele inclusive scan in shared memory: log2(256) = 8 rounds.
    for (uint d = 1u; d < WAVEFRONT_GROUP; d <<= 1u) {
        uint add = l >= d ? scan[l - d] : 0u;
        barrier();
        scan[l] += add;
        barrier();
    }
    if (i < count) counts[i] = scan[l] - own;
    if (l == WAVEFRONT_GROUP - 1u) block_sums[gl_WorkGroupID.x] = scan[l];
}

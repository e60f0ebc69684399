#version 460
// The light simulator's compaction and expansion, second pass (one workgroup): the
// blocks' totals from light_wavefront_scan_blocks.comp become their exclusive offsets,
// 256 at a time with a running carry; the grand total is the next list's size, written
// with its indirect dispatch. A total above the capacity is recorded (CTRL_NEEDED): the
// emit writes what fits and counts the flux it drops, and the host refuses the result.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "light_wavefront.glsl"

shared uint scan[WAVEFRONT_GROUP];

void main() {
    uint l = gl_LocalInvocationID.x;
    uint count = control[CTRL_COUNT + pc.parity];
    uint blocks = (count + WAVEFRONT_GROUP - 1u) / WAVEFRONT_GROUP;
    uint carry = 0u;
    for (uint base = 0u; base < blocks; base += WAVEFRONT_GROUP) {
        uint b = base + l;
        uint own = b < blocks ? block_sums[b] : 0u;
        scan[l] = own;
        barrier();
        for (uint d = 1u; d < WAVEFRONT_GROUP; d <<= 1u) {
            uint add = l >= d ? scan[l - d] : 0u;
            barrier();
            scan[l] += add;
            barrier();
        }
        if (b < blocks) block_sums[b] = carry + scan[l] - own;
        carry += scan[WAVEFRONT_GROUP - 1u];
        barrier();
    }
    if (l == 0u) {
        uint next = min(carry, pc.capacity);
        if (carry > pc.capacity) atomicMax(control[CTRL_NEEDED], carry);
        uint other = 1u - pc.parity;
        control[CTRL_COUNT + other] = next;
        control[CTRL_DISPATCH + 4u * other] = (next + WAVEFRONT_GROUP - 1u) / WAVEFRONT_GROUP;
        control[CTRL_DISPATCH + 4u * other + 1u] = 1u;
        control[CTRL_DISPATCH + 4u * other + 2u] = 1u;
        control[CTRL_PEAK] = max(control[CTRL_PEAK], next);
        // This cycle advanced `count` patches (one add here, not one atomic per patch).
        control[CTRL_PATCH_CYCLES] += count;
    }
}

#version 460
// The compute sweep's splat, second of its dispatches (light_gather.glsl): the bins'
// counts become the offsets of their lists in `bin_list` (an exclusive prefix sum), the
// counts are zeroed for the next plane's deposits and the fill cursors for this plane's
// fill. One workgroup: each invocation sums a run of consecutive bins, invocation 0 scans
// the 256 run sums, each invocation then writes its run's offsets; the same again for the
// pair gather's chunks per fine tile (light_gather.glsl). Every loop's trip
// count is the same for the whole workgroup (llvmpipe runs a loop's body for masked
// lanes too).
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"

layout(local_size_x = 256) in;

shared uint run_start[256];

void main() {
    uint n = bin_count();
    uint t = gl_LocalInvocationIndex;
    uint per = (n + 255u) / 256u;
    uint first = t * per;
    uint sum = 0u;
    for (uint k = 0u; k < per; ++k) {
        uint b = first + k;
        if (b < n) sum += bins[b];
    }
    run_start[t] = sum;
    barrier();
    if (t == 0u) {
        uint running = 0u;
        for (uint k = 0u; k < 256u; ++k) {
            uint s = run_start[k];
            run_start[k] = running;
            running += s;
        }
    }
    barrier();
    uint offset = run_start[t];
    // The pair gather's chunks (light_gather.glsl), from the counts before they are zeroed:
    // each invocation sums a run of fine tiles' chunks, invocation 0 scans the sums, each
    // writes its run's first chunks.
    uint tiles = fine_bins();
    uint per_tile = (tiles + 255u) / 256u;
    uint first_tile = t * per_tile;
    uint chunks = 0u;
    for (uint k = 0u; k < per_tile; ++k) {
        uint tile = first_tile + k;
        if (tile < tiles) chunks += max(1u, (tile_candidates(tile, 0u) + GATHER_CHUNK - 1u) / GATHER_CHUNK);
    }
    barrier();   // every invocation has its offset: run_start is reused
    run_start[t] = chunks;
    barrier();
    if (t == 0u) {
        uint running = 0u;
        for (uint k = 0u; k < 256u; ++k) {
            uint s = run_start[k];
            run_start[k] = running;
            running += s;
        }
        bins[chunk_start_word() + tiles] = running;
    }
    barrier();
    uint chunk = run_start[t];
    for (uint k = 0u; k < per_tile; ++k) {
        uint tile = first_tile + k;
        if (tile < tiles) {
            bins[chunk_start_word() + tile] = chunk;
            chunk += max(1u, (tile_candidates(tile, 0u) + GATHER_CHUNK - 1u) / GATHER_CHUNK);
        }
    }
    // Every invocation has read the counts it needs before any is zeroed.
    barrier();
    for (uint k = 0u; k < per; ++k) {
        uint b = first + k;
        if (b < n) {
            uint c = bins[b];
            bins[n + b] = offset;
            offset += c;
            bins[b] = 0u;
            bins[2u * n + b] = 0u;
        }
    }
}

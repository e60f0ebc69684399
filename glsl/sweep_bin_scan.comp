#version 460
// The compute sweep's splat, second of four dispatches (light_gather.glsl): the bins'
// counts become the offsets of their lists in `bin_list` (an exclusive prefix sum), the
// counts are zeroed for the next plane's deposits and the fill cursors for this plane's
// fill. One workgroup: each invocation sums a run of consecutive bins, invocation 0 scans
// the 256 run sums, each invocation then writes its run's offsets. Every loop's trip
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

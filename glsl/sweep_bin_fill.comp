#version 460
// The compute sweep's splat, third of four dispatches (light_gather.glsl): each light ray
// lists itself in the bins sweep_deposit.comp counted it in, at its bin's offset plus a
// cursor. The order within a bin varies from run to run; the gather's integer sums do
// not depend on it.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy);
    if (!ray_exists(ij)) return;
    int r = ray_index(ij);
    ivec4 range;
    int level = footprint_bins(stored_footprint(r), range);
    if (level == BIN_NONE) return;
    uint n = bin_count();
    for (int y = range.y; y <= range.w; ++y) {
        for (int x = range.x; x <= range.z; ++x) {
            uint b = bin_of(level, ivec2(x, y));
            bin_list[bins[n + b] + atomicAdd(bins[2u * n + b], 1u)] = uint(r);
        }
    }
}

#version 460
// The compute sweep's splat, second half (light_gather.glsl): each 8 x 8 tile of pixels
// lists the blocks of rays whose deposits overlap it, and each pixel sums the deposits of
// those blocks' rays over its own area, in 32.32 fixed point, into this plane's
// irradiance and light direction (layer `read_layer`, the layer the rays were written
// to).
//
// The list lives in shared memory (GATHER_LIST entries). So that it never overflows,
// whatever the caustic: a first scan counts the overlapping blocks per bucket of
// consecutive block indices (GATHER_BUCKETS buckets, each at most GATHER_LIST blocks:
// render/refract checks the ray grid against that), then the buckets are taken in
// rounds that each fit the list. Usually one round. Every loop's trip count is the
// same for the whole workgroup: llvmpipe runs a loop's body at least once even with
// every lane masked, so per-lane trip counts (or many rounds) would cost work that does
// nothing there.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_light.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;
    float unit;       // the fixed-point unit (the light's brightest channel)
} pc;

shared uint list[GATHER_LIST];
shared uint count;
shared uint bucket_count[GATHER_BUCKETS];

bool overlaps(uint b, vec2 lo, vec2 hi) {
    vec4 bb = blocks[b];
    // Overlap of positive area, as deposit_overlap counts it.
    return bb.x < hi.x && bb.z > lo.x && bb.y < hi.y && bb.w > lo.y;
}

void main() {
    ivec2 size = ivec2(P.camera.zw);
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uint t = gl_LocalInvocationIndex;
    vec2 tile_lo = vec2(gl_WorkGroupID.xy * 8u);
    vec2 tile_hi = min(tile_lo + 8.0, vec2(size));
    ivec2 nb = gather_blocks();
    uint total = uint(nb.x * nb.y);
    uint per_bucket = (total + GATHER_BUCKETS - 1u) / GATHER_BUCKETS;
    int columns = int(P.light_rays.x);
    ivec2 grid = ivec2(P.light_rays.xy);

    // Scan 1: overlapping blocks per bucket.
    for (uint k = t; k < GATHER_BUCKETS; k += 64u) bucket_count[k] = 0u;
    if (t == 0u) count = 0u;
    barrier();
    for (uint b = t; b < total; b += 64u) {
        if (overlaps(b, tile_lo, tile_hi)) atomicAdd(bucket_count[b / per_bucket], 1u);
    }
    barrier();
    // The rounds: consecutive buckets while they fit the list (every lane computes the
    // same bounds from shared memory).
    uvec2 sum[SPLAT_GATHER_CHANNELS];
    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) sum[k] = uvec2(0u);
    uint bucket = 0u;
    while (bucket < GATHER_BUCKETS) {
        uint first = bucket;
        uint n = 0u;
        while (bucket < GATHER_BUCKETS && n + bucket_count[bucket] <= GATHER_LIST) {
            n += bucket_count[bucket];
            ++bucket;
        }
        // Scan 2: the blocks of these buckets that overlap the tile, in any order (the
        // sums are integers).
        uint lo = first * per_bucket, hi = min(bucket * per_bucket, total);
        for (uint b = lo + t; b < hi; b += 64u) {
            if (overlaps(b, tile_lo, tile_hi)) list[atomicAdd(count, 1u)] = b;
        }
        barrier();
        uint listed = count;
        for (uint k = 0u; k < listed; ++k) {
            uint b = list[k];
            ivec2 corner = ivec2(int(b) % nb.x, int(b) / nb.x) * GATHER_BLOCK;
            for (int q = 0; q < GATHER_BLOCK * GATHER_BLOCK; ++q) {
                ivec2 ij = corner + ivec2(q % GATHER_BLOCK, q / GATHER_BLOCK);
                if (ij.x >= grid.x || ij.y >= grid.y) continue;
                int r = ij.y * columns + ij.x;
                vec4 footprint = stored_footprint(r);
                // A ray whose deposit misses the tile is skipped by the whole workgroup
                // (on a GPU: most of a block's rays; a deposit is a few pixels, a block's
                // 16).
                if (any(greaterThanEqual(footprint.xy, tile_hi)) || any(lessThanEqual(footprint.zw, tile_lo))) continue;
                if (deposit_overlap(footprint, vec2(pixel)) <= 0.0) continue;
                vec3 e;
                vec4 d;
                deposit_at(load_deposit(r), vec2(pixel), pc.unit, e, d);
                add_fixed_reg(sum[0], e.r);
                add_fixed_reg(sum[1], e.g);
                add_fixed_reg(sum[2], e.b);
                add_fixed_reg(sum[3], d.x);
                add_fixed_reg(sum[4], d.y);
                add_fixed_reg(sum[5], d.z);
                add_fixed_reg(sum[6], d.w);
            }
        }
        barrier();
        if (t == 0u) count = 0u;
        barrier();
    }
    if (any(greaterThanEqual(pixel, size))) return;
    float c[SPLAT_GATHER_CHANNELS];
    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) c[k] = fixed_to_float(sum[k]) * pc.unit;
    ivec3 at = ivec3(pixel, pc.read_layer);
    imageStore(irradiance, at, vec4(c[0], c[1], c[2], 0.0));
    imageStore(irradiance_direction, at, vec4(c[3], c[4], c[5], c[6]));
}

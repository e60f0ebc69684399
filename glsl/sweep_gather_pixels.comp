#version 460
// The compute sweep's splat, last of four dispatches with this gather (light_gather.glsl),
// the `gather=pixels` lever (sweep_gather.comp is the default, `gather=pairs`): each 8 x 8
// tile of pixels reads the rays listed in its bin, its coarse tile's bin and the global bin,
// and each pixel sums the deposits of those rays over its own area, in 32.32 fixed point
// in registers (the atomic splat's integer sums, bit for bit), into this plane's
// irradiance and light direction (layer `read_layer`, the layer the rays were written
// to). The candidates are taken 64 at a time into shared memory (index and footprint; a
// candidate of a coarse or the global bin that misses this tile is dropped there). Every
// loop's trip count is the same for the whole workgroup: llvmpipe runs a loop's body at
// least once even with every lane masked.
// Why a loop over candidates per pixel and not a ray per invocation with shared atomics
// (contention at a focus, measured on an H200): docs/BENCH.md, "The gather splat, binned".
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

shared int candidate[64];
shared vec4 candidate_footprint[64];

void main() {
    ivec2 size = screen_size();
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uint t = gl_LocalInvocationIndex;
    vec2 tile_lo = vec2(gl_WorkGroupID.xy * GATHER_TILE);
    vec2 tile_hi = min(tile_lo + float(GATHER_TILE), vec2(size));
    TileList list = tile_list(ivec2(gl_WorkGroupID.xy));
    uint total = list_length(list);

    uvec2 sum[SPLAT_GATHER_CHANNELS];
    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) sum[k] = uvec2(0u);
    for (uint base = 0u; base < total; base += 64u) {
        uint k = base + t;
        int r = -1;
        vec4 footprint = vec4(0.0);
        if (k < total) {
            r = list_ray(list, k);
            footprint = stored_footprint(r);
            // Overlap of positive area with the tile, as deposit_overlap counts it.
            if (!(footprint.x < tile_hi.x && footprint.z > tile_lo.x && footprint.y < tile_hi.y
                  && footprint.w > tile_lo.y)) r = -1;
        }
        candidate[t] = r;
        candidate_footprint[t] = footprint;
        barrier();
        for (int q = 0; q < 64; ++q) {
            int c = candidate[q];
            if (c < 0) continue;
            if (deposit_overlap(candidate_footprint[q], vec2(pixel)) <= 0.0) continue;
            vec3 e;
            vec4 d;
            deposit_at(load_deposit(c), vec2(pixel), pc.unit, e, d);
            add_fixed_reg(sum[0], e.r);
            add_fixed_reg(sum[1], e.g);
            add_fixed_reg(sum[2], e.b);
            add_fixed_reg(sum[3], d.x);
            add_fixed_reg(sum[4], d.y);
            add_fixed_reg(sum[5], d.z);
            add_fixed_reg(sum[6], d.w);
        }
        barrier();
    }
    if (any(greaterThanEqual(pixel, size))) return;
    float c[SPLAT_GATHER_CHANNELS];
    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) c[k] = fixed_to_float(sum[k]) * pc.unit;
    ivec3 at = ivec3(pixel, pc.read_layer);
    imageStore(irradiance, at, vec4(c[0], c[1], c[2], 0.0));
    imageStore(irradiance_direction, at, vec4(c[3], c[4], c[5], c[6]));
}

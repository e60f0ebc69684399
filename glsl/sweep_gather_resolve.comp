#version 460
// The compute sweep's splat, last of five dispatches with `gather=pairs`
// (light_gather.glsl): the tiles whose candidates took more than one chunk of
// sweep_gather.comp have their sums in `bins`; each such tile's pixels read them, store
// them as this plane's irradiance and light direction (layer `read_layer`, as the gather
// does) and zero them for the next plane. Tiles of one chunk were stored by the gather.
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
    float unit;
} pc;

void main() {
    ivec2 tile = ivec2(gl_WorkGroupID.xy);
    uint tile_index = uint(tile.y * fine_tiles().x + tile.x);
    uint first = bins[chunk_start_word() + tile_index];
    if (bins[chunk_start_word() + tile_index + 1u] - first <= 1u) return;
    uint px = gl_LocalInvocationIndex;
    float c[SPLAT_GATHER_CHANNELS];
    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) {
        uint w = tile_sums_word(tile_index, px, uint(k));
        c[k] = fixed_to_float(uvec2(bins[w], bins[w + 1u])) * pc.unit;
        bins[w] = 0u;
        bins[w + 1u] = 0u;
    }
    ivec2 pixel = tile * int(GATHER_TILE) + ivec2(px % GATHER_TILE, px / GATHER_TILE);
    if (any(greaterThanEqual(pixel, screen_size()))) return;
    ivec3 at = ivec3(pixel, pc.read_layer);
    imageStore(irradiance, at, vec4(c[0], c[1], c[2], 0.0));
    imageStore(irradiance_direction, at, vec4(c[3], c[4], c[5], c[6]));
}

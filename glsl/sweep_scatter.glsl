// The compute sweep's splat as a scatter of ray blocks (the `gather=blocks` lever, issue
// 31): one dispatch over the light-ray grid, a workgroup per block of 8 x 8 neighbouring
// rays, then sweep_scatter_resolve.comp. Built as sweep_scatter_int64.comp and
// sweep_scatter_int64_boxes.comp (64-bit atomics, SPLAT_INT64) where the device has
// shaderBufferInt64Atomics, else as sweep_scatter.comp (two 32-bit words a sum).
//
// Each invocation computes its ray's deposit (light_splat_ray.glsl, the same deposit as
// every other splat). The block's bounds on the screen place a tile of SCATTER_TILE x
// SCATTER_TILE pixels of 32.32 fixed-point sums in shared memory; the block's (ray,
// pixel) pairs are dealt out evenly over the workgroup, each adding its deposit into the
// tile; then the tile's non-zero sums go into the plane's sums (light_splat_fixed.glsl,
// binding 18), one add per pixel and channel.
//
// Why blocks of rays: neighbouring rays deposit next to each other wherever the
// wavefront is smooth, so a block's 64 rays land in a few dozen pixels and the global
// adds are one per pixel the block touches, not one per pair; no deposit is written to
// memory and read back, and there are no bins, lists or tile candidates (the binned
// gather's five dispatches a plane become two). Why the pairs dealt out: with one ray per
// invocation looping over its pixels, a subgroup waits for its widest ray (206 against
// 123 ms a frame on an H100). Why 64-bit atomics: with two words the carry needs the low
// word's old value, and waiting for it made the scatter 2.7 x slower on the H100
// (docs/bench/2026-11-27-nvidia-h100-blocks.md).
//
// The tile sits at the lowest pixel the block's deposits reach when they all fit in it;
// otherwise (a block torn by a silhouette, spread by a lens, or holding wide rays) it is
// centred on their bounds, and each ray whose pixels do not all fall inside it adds
// straight into the plane's sums. Either way every deposit is truncated to 32.32 fixed
// point once and summed as 64-bit integers, and integer addition is associative: the
// sums are the atomic splat's and the binned gathers', bit for bit, in any order.
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#define SPLAT_SUMS_BINDING 18
#include "light_splat_fixed.glsl"
// For the deposit's packing (deposit_to, deposit_from); its buffers are not used here.
#define DEPOSITS_READONLY 1
#include "light_gather.glsl"

#if SPLAT_INT64
// The same sums as 64-bit words (word 2 k + 0 low, 2 k + 1 high is the little-endian
// uint64 k): an add is one atomic whose result nothing waits for.
layout(std430, set = 0, binding = SPLAT_SUMS_BINDING) buffer SplatSums64 {
    uint64_t sums64[];
};
#endif

// Add the 64-bit value w (lo, hi) to the plane's sum at `slot` (an even word index).
void add_to_plane(uint slot, uvec2 w) {
#if SPLAT_INT64
    atomicAdd(sums64[slot / 2u], packUint2x32(w));
#else
    add_words(slot, w);
#endif
}

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    float unit;        // the fixed-point unit (the light's brightest channel)
    ivec2 origin;      // y: the first grid row this plane deposits (the `rays` lever)
    ivec2 extent;      // y: how many
    uint pad;
} pc;

const int TILE = int(SCATTER_TILE);
const uint TILE_PIXELS = SCATTER_TILE * SCATTER_TILE;
// The block's rays are dealt out HALF at a time, their deposits in shared memory: all 64
// at once with the boxes deposit (3 vec4s a ray), in two halves with the cells deposit
// (10 vec4s a ray: 64 of them would not fit in 16 KiB beside the tile).
#ifdef DEPOSIT_BOXES_ONLY
const uint HALF = 64u;
const int SHARED_VEC4S = 3;
#else
const uint HALF = 32u;
const int SHARED_VEC4S = DEPOSIT_VEC4S_MAX;
#endif
const uint HALVES = 64u / HALF;

// The tile's sums: [channel][pixel], 32.32 fixed point in two words (SHARED_SUMS)
// (7 x 144 x 8 bytes at SCATTER_TILE 12), and half the block's deposits (32 x 10 vec4s):
// 13.9 KiB with the rest, within the 16 KiB every device gives a workgroup.
SHARED_SUMS(tile, SPLAT_CHANNELS, TILE_PIXELS);
// The bounds (inclusive, pixels) of the block's deposits on the screen.
shared int bounds_lo_x, bounds_lo_y, bounds_hi_x, bounds_hi_y;
// The half's rays: the rectangle of pixels each deposit overlaps (first.xy, extent.xy;
// zero extent for none), the running end of their (ray, pixel) pairs, whether the
// rectangle lies in the tile, and the deposit.
shared ivec4 ray_rect[HALF];
shared uint ray_end[HALF];
shared uint ray_in_tile[HALF];
shared vec4 ray_deposit_v[HALF * uint(SHARED_VEC4S)];

// Add v, truncated to 32.32 fixed point, to the tile's sum of (channel, pixel t)
// (light_splat_fixed.glsl's SHARED_SUM_ADD: with two words, a positive deposit below 1,
// the light's unit, whose low word does not wrap leaves the high word as it is).
void add_to_tile(uint channel, uint t, float v) {
    if (v == 0.0) return;
    uvec2 w = to_fixed(v);
    SHARED_SUM_ADD(tile, channel, t, w);
}

RayDeposit half_deposit(uint c) {
    vec4 v[DEPOSIT_VEC4S_MAX];
    for (int q = 0; q < DEPOSIT_VEC4S_MAX; ++q) {
        v[q] = q < DEPOSIT_VEC4S ? ray_deposit_v[c * uint(DEPOSIT_VEC4S) + uint(q)] : vec4(0.0);
    }
    return deposit_from(v);
}

// Pair `pair` of the half (of `pairs`): its ray is the first whose running end exceeds
// it (log2 HALF halvings), its pixel the ray's rectangle's, row by row; the deposit there
// goes into the tile or, for a ray outside it, into the plane's sums.
void add_pair(uint pair, uint pairs, ivec2 origin, ivec2 size) {
    uint c_lo = 0u, c_hi = HALF - 1u;
    for (uint s = 1u; s < HALF; s *= 2u) {
        uint mid = (c_lo + c_hi) / 2u;
        bool right = ray_end[mid] <= pair;
        c_lo = right ? mid + 1u : c_lo;
        c_hi = right ? c_hi : mid;
    }
    if (pair >= pairs) return;
    uint c = c_lo;
    ivec4 r = ray_rect[c];
    uint local = pair - (ray_end[c] - uint(r.z * r.w));
    ivec2 at = r.xy + ivec2(int(local) % r.z, int(local) / r.z);
    vec3 e;
    vec4 dir;
    deposit_at(half_deposit(c), vec2(at), pc.unit, e, dir);
    float v[SPLAT_CHANNELS] = float[](e.r, e.g, e.b, dir.x, dir.y, dir.z, dir.w);
    if (ray_in_tile[c] != 0u) {
        uint q = uint((at.y - origin.y) * TILE + (at.x - origin.x));
        for (uint k = 0u; k < SPLAT_CHANNELS; ++k) add_to_tile(k, q, v[k]);
    } else {
        uint pixels = uint(size.x * size.y), p = uint(at.y * size.x + at.x);
        for (uint k = 0u; k < SPLAT_CHANNELS; ++k) {
            if (v[k] != 0.0) add_to_plane(splat_slot(k, p, pixels), to_fixed(v[k]));
        }
    }
}

void main() {
    uint t = gl_LocalInvocationIndex;
    for (uint q = t; q < TILE_PIXELS; q += 64u) {
        for (uint k = 0u; k < SPLAT_CHANNELS; ++k) SHARED_SUM_CLEAR(tile, k, q);
    }
    if (t == 0u) {
        bounds_lo_x = 0x7fffffff;
        bounds_lo_y = 0x7fffffff;
        bounds_hi_x = -0x7fffffff;
        bounds_hi_y = -0x7fffffff;
    }
    barrier();

    // This ray's deposit and the pixels it overlaps with positive area on the screen
    // (pixel p is the square [p, p + 1]: from floor(lo) to ceil(hi) - 1).
    ivec2 size = ivec2(P.camera.zw);
    ivec2 ij = DEPOSITED_RAY;
    RayDeposit d;
    bool has = DEPOSITS_HERE(ij) && ray_deposit(ray_index(ij), pc.read_layer, pc.depth, d);
    if (!has) clear_deposit(d);
    ivec2 first = ivec2(0), last = ivec2(-1);
    if (has) {
        first = max(ivec2(floor(d.footprint.xy)), ivec2(0));
        last = min(ivec2(ceil(d.footprint.zw)) - 1, size - 1);
        has = all(lessThanEqual(first, last));
    }
    if (has) {
        atomicMin(bounds_lo_x, first.x);
        atomicMin(bounds_lo_y, first.y);
        atomicMax(bounds_hi_x, last.x);
        atomicMax(bounds_hi_y, last.y);
    }
    barrier();
    ivec2 lo = ivec2(bounds_lo_x, bounds_lo_y), hi = ivec2(bounds_hi_x, bounds_hi_y);
    // (No deposit in the block: the bounds are empty, nothing is added or flushed.)
    bool fits = all(lessThanEqual(lo, hi)) && all(lessThan(hi - lo, ivec2(TILE)));
    ivec2 origin = fits ? lo : (lo + hi) / 2 - TILE / 2;
    bool in_tile = all(greaterThanEqual(first, origin)) && all(lessThan(last, origin + TILE));
    vec4 packed[DEPOSIT_VEC4S_MAX];
    deposit_to(d, packed);

    // The (ray, pixel) pairs dealt out evenly, HALF rays at a time: a ray whose deposit
    // covers many pixels does not hold up the others.
    for (uint half_index = 0u; half_index < HALVES; ++half_index) {
        if (t / HALF == half_index) {
            uint c = t % HALF;
            ray_rect[c] = has ? ivec4(first, last - first + 1) : ivec4(0);
            ray_in_tile[c] = in_tile ? 1u : 0u;
            for (int q = 0; q < DEPOSIT_VEC4S; ++q) {
                ray_deposit_v[c * uint(DEPOSIT_VEC4S) + uint(q)] = packed[q];
            }
        }
        barrier();
        if (t < HALF) {
            uint end = 0u;
            for (uint c = 0u; c <= t; ++c) end += uint(ray_rect[c].z * ray_rect[c].w);
            ray_end[t] = end;
        }
        barrier();
        uint pairs = ray_end[HALF - 1u];
        for (uint p0 = 0u; p0 < pairs; p0 += 64u) add_pair(p0 + t, pairs, origin, size);
        barrier();
    }

    // The tile's pixels within the block's bounds into the plane's sums.
    ivec2 from = max(origin, lo), to = min(origin + TILE - 1, hi);
    uint pixels = uint(size.x * size.y);
    for (uint q = t; q < TILE_PIXELS; q += 64u) {
        ivec2 p = origin + ivec2(int(q) % TILE, int(q) / TILE);
        if (any(lessThan(p, from)) || any(greaterThan(p, to))) continue;
        uint pixel = uint(p.y * size.x + p.x);
        for (uint k = 0u; k < SPLAT_CHANNELS; ++k) {
            uvec2 w = SHARED_SUM_GET(tile, k, q);
            if ((w.x | w.y) != 0u) add_to_plane(splat_slot(k, pixel, pixels), w);
        }
    }
}

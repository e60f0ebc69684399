#version 460
// The compute sweep's splat, fourth of five dispatches (light_gather.glsl), the
// `gather=pairs` lever (the default): each 8 x 8 tile of pixels reads the rays listed in
// its bin, its coarse tile's bin and the global bin, in chunks of GATHER_CHUNK, one
// workgroup per chunk (a tile of more than one chunk adds its sums into `bins` for
// sweep_gather_resolve.comp), 64 rays at a time, and spreads the work over the
// (ray, pixel) pairs where a deposit lands: every invocation evaluates one deposit at one
// pixel of the tile, and adds it to that pixel's seven 32.32 fixed-point sums in shared
// memory with integer atomics (light_splat_fixed.glsl's two-word carry: the sums are the
// atomic splat's and sweep_gather_pixels.comp's, bit for bit, in any order).
//
// Why pairs: in sweep_gather_pixels.comp (`gather=pixels`) each invocation is a pixel and
// loops over every candidate, so a ray whose deposit covers 2 to 4 of the tile's pixels
// costs the whole 32-wide subgroup one deposit evaluation and seven 64-bit adds; here it
// costs 2 to 4 invocations. And why not one ray per invocation looping over its pixels
// (tried, docs/bench/2026-11-26-nvidia-h200-gather.md): a subgroup then waits for its
// widest ray (a coarse ray covers up to all 64 pixels of a tile); pairs are dealt out
// evenly whatever the rays' sizes.
//
// The workgroups are fewer than the chunks only where many tiles have more than one: a
// workgroup then takes every so many chunks in turn.
//
// Per batch of 64 candidates, three steps with a barrier after each:
//   1. invocation t takes candidate t: its ray and the rectangle of the tile's pixels its
//      footprint overlaps with positive area (deposit_overlap > 0), possibly empty;
//   2. each invocation sums the pair counts up to its candidate (the batch's pairs are
//      numbered candidate by candidate), and the invocations copy the batch's deposits
//      into shared memory, consecutive invocations reading consecutive vec4s;
//   3. pair k = base + t: its candidate by binary search in the running sums, its pixel in
//      that candidate's rectangle, row by row; deposit_at and seven fixed-point adds.
// Every loop's trip count is the same for the whole workgroup (llvmpipe runs a loop's
// body even with every lane masked).
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

const uint BATCH = 64u;

// The tile's sums: [channel][pixel], 32.32 fixed point in two words (SHARED_SUMS,
// light_splat_fixed.glsl).
SHARED_SUMS(sum, SPLAT_GATHER_CHANNELS, 64);
// The batch: each candidate's rectangle in the tile (x0, y0, width, height, 8 bits each;
// zero pixels for a ray that misses the tile), its pairs' running end, and its deposit.
shared uint candidate_rect[BATCH];
shared uint candidate_end[BATCH];
shared int candidate_ray[BATCH];
shared vec4 candidate_deposit[BATCH * uint(DEPOSIT_VEC4S_MAX)];

// The rectangle of the tile's pixels (tile-local, x0 y0 x1 y1 exclusive) that footprint
// f overlaps with positive area: pixel p (the square [p, p + 1]) overlaps [lo, hi] where
// lo < p + 1 and p < hi, so p runs from floor(lo) to ceil(hi) - 1.
ivec4 tile_rect(vec4 f, ivec2 tile_lo, ivec2 tile_size) {
    ivec2 p0 = ivec2(clamp(floor(f.xy), vec2(tile_lo), vec2(tile_lo + tile_size)));
    ivec2 p1 = ivec2(clamp(ceil(f.zw), vec2(tile_lo), vec2(tile_lo + tile_size)));
    bool empty = !(f.x < f.z && f.y < f.w) || any(lessThanEqual(p1, p0));
    return empty ? ivec4(0) : ivec4(p0 - tile_lo, p1 - tile_lo);
}

RayDeposit shared_deposit(uint c) {
    uint k = c * uint(DEPOSIT_VEC4S);
    vec4 v[DEPOSIT_VEC4S_MAX];
    for (int q = 0; q < DEPOSIT_VEC4S_MAX; ++q) {
        v[q] = q < DEPOSIT_VEC4S ? candidate_deposit[k + uint(q)] : vec4(0.0);
    }
    return deposit_from(v);
}

// Add v, truncated to 32.32 fixed point as add_fixed_reg does, to the shared sum of
// (channel, pixel) (SHARED_SUM_ADD, light_splat_fixed.glsl).
void add_fixed_shared(uint channel, uint px, float v) {
    uvec2 w = to_fixed(v);
    SHARED_SUM_ADD(sum, channel, px, w);
}

// The last tile whose first chunk is at or before `chunk` (first chunks ascend; the loop
// runs for any number of tiles up to 2^24, the same for every invocation). Where every
// tile up to `chunk` is one chunk (the common case), chunk c is tile c's only one (first
// chunks are at least their tile's index) and the search is skipped.
uint tile_of_chunk(uint chunk) {
    uint tiles = fine_bins();
    bool direct = chunk < tiles && bins[chunk_start_word() + chunk] == chunk;
    uint lo = direct ? chunk : 0u, hi = direct ? chunk : tiles - 1u;
    for (int s = 0; s < 24; ++s) {
        uint mid = (lo + hi + 1u) / 2u;
        bool left = bins[chunk_start_word() + mid] <= chunk;
        lo = left ? mid : lo;
        hi = left ? hi : mid - 1u;
    }
    return lo;
}

// One (ray, pixel) pair of the batch: its candidate is the first whose running end
// exceeds `pair` (candidate_end is non-decreasing; 6 halvings of 64); its deposit at its
// pixel is added into the tile's sums in shared memory.
void add_pair(uint pair, uint pairs, ivec2 tile_lo) {
    uint c_lo = 0u, c_hi = BATCH - 1u;
    for (int s = 0; s < 6; ++s) {
        uint mid = (c_lo + c_hi) / 2u;
        bool right = candidate_end[mid] <= pair;
        c_lo = right ? mid + 1u : c_lo;
        c_hi = right ? c_hi : mid;
    }
    if (pair < pairs) {
        uint c = c_lo;
        uint e = candidate_rect[c];
        uint width = e >> 16 & 0xffu, height = e >> 24;
        uint local = pair - (candidate_end[c] - width * height);
        ivec2 at = ivec2(e & 0xffu, e >> 8 & 0xffu) + ivec2(local % width, local / width);
        vec3 irr;
        vec4 dir;
        deposit_at(shared_deposit(c), vec2(tile_lo + at), pc.unit, irr, dir);
        uint px = uint(at.y) * GATHER_TILE + uint(at.x);
        add_fixed_shared(0u, px, irr.r);
        add_fixed_shared(1u, px, irr.g);
        add_fixed_shared(2u, px, irr.b);
        add_fixed_shared(3u, px, dir.x);
        add_fixed_shared(4u, px, dir.y);
        add_fixed_shared(5u, px, dir.z);
        add_fixed_shared(6u, px, dir.w);
    }
}

// Invocation t's pixel of the tile: stored when the tile is one chunk, else added into
// the tile's sums in `bins` for sweep_gather_resolve.comp.
void store_tile_pixel(uint tile_index, ivec2 tile_lo, bool several_chunks, ivec2 size) {
    uint t = gl_LocalInvocationIndex;
    ivec2 local_px = ivec2(t % GATHER_TILE, t / GATHER_TILE);
    ivec2 pixel = tile_lo + local_px;
    if (several_chunks) {
        for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) {
            uint w = tile_sums_word(tile_index, t, uint(k));
            uvec2 s = SHARED_SUM_GET(sum, k, t);
            uint old = atomicAdd(bins[w], s.x);
            uint carry = old + s.x < old ? 1u : 0u;
            atomicAdd(bins[w + 1u], s.y + carry);
        }
    } else if (all(lessThan(pixel, size))) {
        float c[SPLAT_GATHER_CHANNELS];
        for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) {
            c[k] = fixed_to_float(SHARED_SUM_GET(sum, k, t)) * pc.unit;
        }
        ivec3 at = ivec3(pixel, pc.read_layer);
        imageStore(irradiance, at, vec4(c[0], c[1], c[2], 0.0));
        imageStore(irradiance_direction, at, vec4(c[3], c[4], c[5], c[6]));
    }
}

// Chunk `chunk` of the frame: its tile's candidates from (chunk - the tile's first chunk)
// * GATHER_CHUNK, at most GATHER_CHUNK of them, summed into the tile's pixels.
void gather_chunk(uint chunk, ivec2 size) {
    uint t = gl_LocalInvocationIndex;
    uint tile_index = tile_of_chunk(chunk);
    uint first_chunk = bins[chunk_start_word() + tile_index];
    uint chunks = bins[chunk_start_word() + tile_index + 1u] - first_chunk;
    ivec2 tile = ivec2(int(tile_index) % fine_tiles().x, int(tile_index) / fine_tiles().x);
    ivec2 tile_lo = tile * int(GATHER_TILE);
    ivec2 tile_size = min(ivec2(GATHER_TILE), size - tile_lo);
    TileList list = tile_list(tile);
    uint total = list_length(list);
    uint begin = (chunk - first_chunk) * GATHER_CHUNK;
    uint end = min(total, begin + GATHER_CHUNK);

    for (int k = 0; k < SPLAT_GATHER_CHANNELS; ++k) SHARED_SUM_CLEAR(sum, k, t);
    for (uint base = begin; base < end; base += BATCH) {
        // 1. Candidate t and its rectangle in the tile.
        uint k = base + t;
        int r = -1;
        ivec4 rect = ivec4(0);
        if (k < end) {
            r = list_ray(list, k);
            rect = tile_rect(stored_footprint(r), tile_lo, tile_size);
        }
        ivec2 extent = rect.zw - rect.xy;
        candidate_rect[t] = uint(rect.x) | uint(rect.y) << 8 | uint(extent.x) << 16
                            | uint(extent.y) << 24;
        candidate_ray[t] = extent.x * extent.y > 0 ? r : -1;
        barrier();
        // 2. The running end of the pairs up to candidate t, and the deposits.
        uint pair_end = 0u, pairs = 0u;
        for (uint c = 0u; c < BATCH; ++c) {
            uint e = candidate_rect[c];
            uint count = (e >> 16 & 0xffu) * (e >> 24);
            pairs += count;
            pair_end += c <= t ? count : 0u;
        }
        candidate_end[t] = pair_end;
        for (uint q = t; q < BATCH * uint(DEPOSIT_VEC4S); q += BATCH) {
            int ray = candidate_ray[q / uint(DEPOSIT_VEC4S)];
            if (ray >= 0) {
                candidate_deposit[q] =
                    deposits[DEPOSIT_VEC4S * ray + int(q % uint(DEPOSIT_VEC4S))];
            }
        }
        barrier();
        // 3. The pairs, 64 at a time.
        for (uint p0 = 0u; p0 < pairs; p0 += BATCH) {
            add_pair(p0 + t, pairs, tile_lo);
        }
        barrier();
    }
    store_tile_pixel(tile_index, tile_lo, chunks > 1u, size);
    barrier();   // the next chunk of this workgroup reuses the shared sums
}

void main() {
    ivec2 size = screen_size();
    uint chunks = bins[chunk_start_word() + fine_bins()];
    for (uint chunk = gl_WorkGroupID.x; chunk < chunks; chunk += gl_NumWorkGroups.x) {
        gather_chunk(chunk, size);
    }
}

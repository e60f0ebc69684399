// The compute sweep's splat as a tile-binned gather (issue 31): no global atomics on the
// sums. Per plane, four dispatches and, with `gather=pairs`, a fifth: sweep_deposit.comp
// computes each light ray's deposit (light_splat_ray.glsl: the same deposit as the point
// sprites and the atomic compute splat) into `deposits` and counts the ray into the bins
// of the tiles it overlaps; sweep_bin_scan.comp turns the counts into list offsets (and
// each tile's first chunk); sweep_bin_fill.comp lists each ray in its bins;
// sweep_gather.comp (pairs: each workgroup a chunk of a tile's rays, each invocation a
// ray and a pixel) or sweep_gather_pixels.comp (each pixel over all its tile's rays) sums
// the deposits; sweep_gather_resolve.comp stores the tiles of several chunks. The sum is
// the atomic splat's: every deposit truncated to 32.32 fixed point
// (light_splat_fixed.glsl) and added as a 64-bit integer, in registers or shared memory
// (integer addition is associative: the result does not depend on the order, and is bit
// for bit the atomic splat's).
#ifndef REFRAKT_LIGHT_GATHER_GLSL
#define REFRAKT_LIGHT_GATHER_GLSL

#include "light_splat_fixed.glsl"

#define SPLAT_GATHER_CHANNELS SPLAT_CHANNELS

// Per ray r (of the grid, r = j * columns + i): its RayDeposit (light_splat_ray.glsl) in
// DEPOSIT_VEC4S vec4s from DEPOSIT_VEC4S r: footprint (an empty one, zero width: no
// deposit), direction (xyz), box amplitude, and with the cells deposit the box, corner
// fluxes A, B, C, D, corners A B, corners C D. The boxes deposit's footprint is its box
// (box_of_ray), so it stores only the first three: 48 bytes a ray instead of 160 (each
// ray's deposit is written and read once or more per plane: on the H100 the splat is
// bound by these bytes, docs/NOTES.md "The splat is bound by bytes").
// DEPOSITS_READONLY 1: the point sprites' shaders, which only read them (a vertex shader
// may not write a storage buffer without vertexPipelineStoresAndAtomics).
#ifndef DEPOSITS_READONLY
#define DEPOSITS_READONLY 0
#endif
#if DEPOSITS_READONLY
layout(std430, set = 0, binding = 20) readonly buffer Deposits {
#else
layout(std430, set = 0, binding = 20) buffer Deposits {
#endif
    vec4 deposits[];
};
const int DEPOSIT_VEC4S = DEPOSIT_CELLS ? 10 : 3;
const int DEPOSIT_VEC4S_MAX = 10;

// A deposit as its DEPOSIT_VEC4S vec4s (the rest zero), as stored and as deposit_from
// reads them.
void deposit_to(RayDeposit d, out vec4 v[DEPOSIT_VEC4S_MAX]) {
    v[0] = d.footprint;
    v[1] = vec4(d.direction, 0.0);
    v[2] = d.box_amplitude;
    v[3] = DEPOSIT_CELLS ? d.box : vec4(0.0);
    v[4] = DEPOSIT_CELLS ? d.flux_a : vec4(0.0);
    v[5] = DEPOSIT_CELLS ? d.flux_b : vec4(0.0);
    v[6] = DEPOSIT_CELLS ? d.flux_c : vec4(0.0);
    v[7] = DEPOSIT_CELLS ? d.flux_d : vec4(0.0);
    v[8] = DEPOSIT_CELLS ? d.corners_ab : vec4(0.0);
    v[9] = DEPOSIT_CELLS ? d.corners_cd : vec4(0.0);
}

#if !DEPOSITS_READONLY
void store_deposit(int r, RayDeposit d) {
    vec4 v[DEPOSIT_VEC4S_MAX];
    deposit_to(d, v);
    for (int k = 0; k < DEPOSIT_VEC4S; ++k) deposits[DEPOSIT_VEC4S * r + k] = v[k];
}
#endif

vec4 stored_footprint(int r) { return deposits[DEPOSIT_VEC4S * r]; }

// A deposit from its DEPOSIT_VEC4S vec4s (`v`, as stored; the cells' fields zero with
// the boxes deposit).
RayDeposit deposit_from(vec4 v[DEPOSIT_VEC4S_MAX]) {
    RayDeposit d;
    d.footprint = v[0];
    d.direction = v[1].xyz;
    d.box_amplitude = v[2];
    d.box = DEPOSIT_CELLS ? v[3] : v[0];
    d.flux_a = DEPOSIT_CELLS ? v[4] : vec4(0.0);
    d.flux_b = DEPOSIT_CELLS ? v[5] : vec4(0.0);
    d.flux_c = DEPOSIT_CELLS ? v[6] : vec4(0.0);
    d.flux_d = DEPOSIT_CELLS ? v[7] : vec4(0.0);
    d.corners_ab = DEPOSIT_CELLS ? v[8] : vec4(0.0);
    d.corners_cd = DEPOSIT_CELLS ? v[9] : vec4(0.0);
    return d;
}

RayDeposit load_deposit(int r) {
    vec4 v[DEPOSIT_VEC4S_MAX];
    for (int k = 0; k < DEPOSIT_VEC4S_MAX; ++k) {
        v[k] = k < DEPOSIT_VEC4S ? deposits[DEPOSIT_VEC4S * r + k] : vec4(0.0);
    }
    return deposit_from(v);
}
// The bins (a counting sort of the rays by the screen tiles their deposits overlap, per
// plane): every ray whose footprint spans at most 2 x 2 tiles of GATHER_TILE pixels goes
// into each of those tiles' bins (fine); one that spans more but at most 2 x 2 coarse
// tiles of GATHER_COARSE_TILE pixels into those coarse tiles' bins; any wider one into
// the one global bin. A ray is listed at most four times, so a list of 4 entries per ray
// never overflows, whatever the caustic. The gather of a fine tile reads its own bin, its
// coarse tile's and the global one.
//
// `bins` holds three arrays of bin_count() words: the count (sweep_deposit.comp adds
// one per listed ray), the offset of each bin's list in `bin_list` (sweep_bin_scan.comp,
// an exclusive prefix sum, which also zeroes the counts for the next plane and the fill
// cursors), and the fill cursor (sweep_bin_fill.comp; afterwards the bin's length).
#if DEPOSITS_READONLY
#define GATHER_BUFFER readonly buffer
#else
#define GATHER_BUFFER buffer
#endif
layout(std430, set = 0, binding = 21) GATHER_BUFFER Bins {
    uint bins[];
};
layout(std430, set = 0, binding = 22) GATHER_BUFFER BinList {
    uint bin_list[];
};

#ifndef GATHER_TILE
#error "GATHER_TILE comes from build.rs (src/render/limits.rs)"
#endif
const int FINE_PER_COARSE = int(GATHER_COARSE_TILE / GATHER_TILE);

ivec2 screen_size() { return ivec2(P.camera.zw); }
ivec2 fine_tiles() { return (screen_size() + int(GATHER_TILE) - 1) / int(GATHER_TILE); }
ivec2 coarse_tiles() {
    return (screen_size() + int(GATHER_COARSE_TILE) - 1) / int(GATHER_COARSE_TILE);
}
uint fine_bins() { ivec2 n = fine_tiles(); return uint(n.x * n.y); }
uint coarse_bins() { ivec2 n = coarse_tiles(); return uint(n.x * n.y); }
uint bin_count() { return fine_bins() + coarse_bins() + 1u; }

const int BIN_NONE = 0, BIN_FINE = 1, BIN_COARSE = 2, BIN_GLOBAL = 3;


// The level a footprint (lo.xy, hi.xy in pixels) is binned at, and the inclusive range of
// that level's tiles (xy first, zw last) it overlaps with positive area inside the screen
// (a tile of side s holds the pixels [s t, s t + s), pixel p the square [p, p + 1]:
// t0 = floor(lo / s), t1 = ceil(hi / s) - 1, exact in floats). BIN_NONE for an empty
// footprint or one off screen; the global bin's range is (0, 0, 0, 0).
int footprint_bins(vec4 footprint, out ivec4 range) {
    range = ivec4(0);
    vec2 lo = max(footprint.xy, vec2(0.0));
    vec2 hi = min(footprint.zw, vec2(screen_size()));
    if (!(lo.x < hi.x && lo.y < hi.y)) return BIN_NONE;
    ivec2 t0 = ivec2(floor(lo / float(GATHER_TILE)));
    ivec2 t1 = ivec2(ceil(hi / float(GATHER_TILE))) - 1;
    if (all(lessThanEqual(t1 - t0, ivec2(int(GATHER_FINE_SPAN) - 1)))) {
        range = ivec4(t0, t1);
        return BIN_FINE;
    }
    ivec2 c0 = t0 / FINE_PER_COARSE, c1 = t1 / FINE_PER_COARSE;
    if (all(lessThanEqual(c1 - c0, ivec2(1)))) {
        range = ivec4(c0, c1);
        return BIN_COARSE;
    }
    return BIN_GLOBAL;
}

uint bin_of(int level, ivec2 t) {
    if (level == BIN_FINE) return uint(t.y * fine_tiles().x + t.x);
    if (level == BIN_COARSE) return fine_bins() + uint(t.y * coarse_tiles().x + t.x);
    return fine_bins() + coarse_bins();
}

// The pair gather's chunks (sweep_gather.comp): a fine tile's candidates (its bin's, its
// coarse tile's and the global bin's) are split into chunks of GATHER_CHUNK, one
// workgroup each, so that a tile where a caustic focuses tens of thousands of rays is
// summed by as many workgroups as it needs rather than by one for all of them (the
// dispatch waits for its slowest workgroup). After the three arrays above, `bins` holds
// fine_bins() + 1 words: the first chunk of each fine tile (sweep_bin_scan.comp, an
// exclusive prefix sum of max(1, ceil(candidates / GATHER_CHUNK))), the last word the
// number of chunks; then the fixed-point sums of the tiles of more than one chunk, 64
// pixels by SPLAT_GATHER_CHANNELS channels by (low, high) words per fine tile, which
// their chunks add into with atomics and sweep_gather_resolve.comp turns into irradiance
// and zeroes for the next plane.
uint chunk_start_word() { return 3u * bin_count(); }
uint tile_sums_word(uint tile, uint px, uint channel) {
    return 3u * bin_count() + fine_bins() + 1u
           + 2u * ((tile * 64u + px) * uint(SPLAT_GATHER_CHANNELS) + channel);
}
// Candidates of fine tile `tile` (index t.y * columns + t.x): its bin's, its coarse
// tile's, the global bin's, as array `array` of `bins` counts them (0: the counts, before
// sweep_bin_scan.comp zeroes them; 2: the lengths, after sweep_bin_fill.comp).
uint tile_candidates(uint tile, uint array) {
    uint a = array * bin_count();
    ivec2 t = ivec2(int(tile) % fine_tiles().x, int(tile) / fine_tiles().x);
    return bins[a + tile] + bins[a + bin_of(BIN_COARSE, t / FINE_PER_COARSE)]
           + bins[a + bin_of(BIN_GLOBAL, ivec2(0))];
}

// A fine tile's candidate list as the gathers read it (after sweep_bin_fill.comp): the
// three bins it reads, and their lengths.
struct TileList {
    uint fine, coarse, wide;
    uint n_fine, n_coarse, n_wide;
};

TileList tile_list(ivec2 tile) {
    uint n = bin_count();
    TileList l;
    l.fine = bin_of(BIN_FINE, tile);
    l.coarse = bin_of(BIN_COARSE, tile / FINE_PER_COARSE);
    l.wide = bin_of(BIN_GLOBAL, ivec2(0));
    l.n_fine = bins[2u * n + l.fine];
    l.n_coarse = bins[2u * n + l.coarse];
    l.n_wide = bins[2u * n + l.wide];
    return l;
}

uint list_length(TileList l) { return l.n_fine + l.n_coarse + l.n_wide; }

// The ray of candidate k (< list_length) of the list: its bin's, then its coarse tile's,
// then the global bin's.
int list_ray(TileList l, uint k) {
    uint n = bin_count();
    uint slot = k < l.n_fine ? bins[n + l.fine] + k
              : k < l.n_fine + l.n_coarse ? bins[n + l.coarse] + (k - l.n_fine)
              : bins[n + l.wide] + (k - l.n_fine - l.n_coarse);
    return int(bin_list[slot]);
}

// The bins' atomics aggregated per workgroup (sweep_deposit.comp, sweep_bin_fill.comp):
// the 64 rays of a workgroup are neighbours, and where a caustic focuses they all fall into
// the same one or two bins, so one atomic per bin and workgroup replaces one per ray
// (per-ray atomics waited on the few counters of a focus: docs/NOTES.md, "The splat is
// bound by bytes" and BENCH.md's H100 pairs). A table of
// BIN_SLOTS bins in shared memory (open addressing, keys bin + 1, 0 empty): each entry
// claims its bin's slot and takes its rank among the slot's entries; a bin that finds the
// table full falls back to its own global atomic.
// (Compute shaders only: not in the point sprites' stages, which include this file for
// the deposits.)
#if !DEPOSITS_READONLY
#define BIN_SLOTS 64u
shared uint slot_bin[BIN_SLOTS];
shared uint slot_count[BIN_SLOTS];
shared uint slot_base[BIN_SLOTS];

// Empty the table: one slot per invocation (the workgroups are 8 x 8); a barrier must
// follow before slot_add.
void slots_clear() {
    slot_bin[gl_LocalInvocationIndex] = 0u;
    slot_count[gl_LocalInvocationIndex] = 0u;
}

// Bin b's slot and this entry's rank in it; -1 when the table is full.
int slot_add(uint b, out uint rank) {
    uint h = (b * 2654435761u) >> 26;   // 6 bits: BIN_SLOTS = 64
    for (uint probe = 0u; probe < BIN_SLOTS; ++probe) {
        uint s = (h + probe) & (BIN_SLOTS - 1u);
        uint prev = atomicCompSwap(slot_bin[s], 0u, b + 1u);
        if (prev == 0u || prev == b + 1u) {
            rank = atomicAdd(slot_count[s], 1u);
            return int(s);
        }
    }
    rank = 0u;
    return -1;
}
#endif

#endif

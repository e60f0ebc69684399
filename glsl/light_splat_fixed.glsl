// The splat's 32.32 fixed-point sums (every splat but the point sprites: the compute
// splat `splat=compute`, the compute sweep's gathers and its scatter of ray blocks): per
// pixel seven channels (irradiance rgb, luminance-weighted direction xyz, luminance
// weight), each a signed 32.32 fixed-point number in two words (low, high). With
// SPLAT_SUMS_BINDING defined, the plane's sums are one storage buffer at that binding,
// channel-major: word 2 * (channel * pixels + pixel) + (0 low, 1 high).
//
// Why fixed point: integer addition is associative, so the sum of the deposits does not
// depend on the order the GPU runs the rays in and every frame is bit-reproducible (float
// atomics would not be, and are an optional feature). Why two words: core Vulkan has 32-bit
// atomics only (64-bit ones are optional); the low word's atomicAdd returns its old value,
// from which the carry into the high word follows exactly, so the pair sums like one
// 64-bit integer modulo 2^64. Values are in units of the light's brightest channel (push
// constant), so 32 integer bits hold the flux of 2^31 rays focused into one pixel and the
// resolution is 2^-32 of the light's brightness (a float32 sum of the same deposits
// rounds at 2^-24 of the running sum).
#ifndef REFRAKT_LIGHT_SPLAT_FIXED_GLSL
#define REFRAKT_LIGHT_SPLAT_FIXED_GLSL

#define SPLAT_CHANNELS 7

// v truncated to 32.32 fixed point, as (lo, hi) words of a 64-bit two's complement
// number. Branch-free (llvmpipe runs both sides of a branch): 0 is (0, 0), a negative
// value the two's complement of its magnitude's. |v| < 2^31.
uvec2 to_fixed(float v) {
    float m = abs(v);
    float f = floor(m);
    uint hi = uint(f);
    // m - f is exact (the fraction of a float), and so is scaling it by 2^32.
    uint lo = uint((m - f) * 4294967296.0);
    bool negative = v < 0.0;
    uint hi_n = ~hi + (lo == 0u ? 1u : 0u);
    uint lo_n = 0u - lo;
    return negative ? uvec2(lo_n, hi_n) : uvec2(lo, hi);
}

// A 64-bit fixed-point sum in registers: (lo, hi) words.
void add_fixed_reg(inout uvec2 sum, float v) {
    uvec2 w = to_fixed(v);
    uint carry;
    sum.x = uaddCarry(sum.x, w.x, carry);
    sum.y = sum.y + w.y + carry;
}

float fixed_to_float(uvec2 sum) {
    uint lo = sum.x, hi = sum.y;
    bool negative = int(hi) < 0;
    if (negative) {
        hi = ~hi + (lo == 0u ? 1u : 0u);
        lo = 0u - lo;
    }
    float m = float(hi) + float(lo) * (1.0 / 4294967296.0);
    return negative ? -m : m;
}

// Sums in shared memory (a workgroup's tile) as two words, the low word's old value
// giving the carry, even where the device has 64-bit atomics: on an H100 one 64-bit
// shared atomic per sum made the pair gather 1.9 x slower (163.7 against 86.6 ms a frame
// on the default scene at 768²; docs/bench/2026-11-27-nvidia-h100-blocks.md), while in
// global memory it is the two words that are slow. Macros, as GLSL passes no shared array
// to a function: SHARED_SUMS declares `name` [channels][n]; SHARED_SUM_ADD adds the
// words w (uvec2 lo, hi; a positive value below 1 whose low word does not wrap leaves
// the high word as it is: one atomic, not two); SHARED_SUM_GET reads them;
// SHARED_SUM_CLEAR zeroes one.
#define SHARED_SUMS(name, channels, n) \
    shared uint name##_lo[channels][n]; \
    shared uint name##_hi[channels][n]
#define SHARED_SUM_ADD(name, k, i, w) \
    { \
        uint old_ = atomicAdd(name##_lo[k][i], (w).x); \
        uint h_ = (w).y + (old_ + (w).x < old_ ? 1u : 0u); \
        if (h_ != 0u) atomicAdd(name##_hi[k][i], h_); \
    }
#define SHARED_SUM_GET(name, k, i) uvec2(name##_lo[k][i], name##_hi[k][i])
#define SHARED_SUM_CLEAR(name, k, i) \
    { \
        name##_lo[k][i] = 0u; \
        name##_hi[k][i] = 0u; \
    }

#ifdef SPLAT_SUMS_BINDING
layout(std430, set = 0, binding = SPLAT_SUMS_BINDING) buffer SplatSums {
    uint sums[];
};

uint splat_slot(uint channel, uint pixel, uint pixels) {
    return 2u * (channel * pixels + pixel);
}

// Add the 64-bit (lo, hi) to the sum at `slot`: the low word's old value tells whether
// it wrapped, and the carry goes into the high word.
void add_words(uint slot, uvec2 w) {
    uint old = atomicAdd(sums[slot], w.x);
    uint h = w.y + (old + w.x < old ? 1u : 0u);
    if (h != 0u) atomicAdd(sums[slot + 1u], h);
}

// Add v (|v| < 2^31) to the sum at `slot`, truncated to a multiple of 2^-32.
void add_fixed(uint slot, float v) {
    if (v == 0.0) return;
    add_words(slot, to_fixed(v));
}

// Pixel `pixel`'s seven sums in the light's units (`unit`): irradiance (rgb) and the
// luminance-weighted direction and weight; zeroed for the next plane.
void take_sums(uint pixel, uint pixels, float unit, out vec3 irradiance_rgb, out vec4 weighted) {
    float c[SPLAT_CHANNELS];
    for (uint k = 0u; k < SPLAT_CHANNELS; ++k) {
        uint slot = splat_slot(k, pixel, pixels);
        c[k] = fixed_to_float(uvec2(sums[slot], sums[slot + 1u])) * unit;
        sums[slot] = 0u;
        sums[slot + 1u] = 0u;
    }
    irradiance_rgb = vec3(c[0], c[1], c[2]);
    weighted = vec4(c[3], c[4], c[5], c[6]);
}
#endif

#endif

// The compute splat's sums (the `splat=compute` lever): per pixel seven channels
// (irradiance rgb, luminance-weighted direction xyz, luminance weight), each a signed
// 32.32 fixed-point number in two words (low, high) of one storage buffer, channel-major:
// word 2 * (channel * pixels + pixel) + (0 low, 1 high).
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

layout(std430, set = 0, binding = SPLAT_SUMS_BINDING) buffer SplatSums {
    uint sums[];
};

uint splat_slot(uint channel, uint pixel, uint pixels) {
    return 2u * (channel * pixels + pixel);
}

// Two's complement negation of the 64-bit (hi, lo).
void negate64(inout uint hi, inout uint lo) {
    hi = ~hi + (lo == 0u ? 1u : 0u);
    lo = 0u - lo;
}

// Add v (|v| < 2^31) to the sum at `slot`, truncated to a multiple of 2^-32.
void add_fixed(uint slot, float v) {
    if (v == 0.0) return;
    float m = abs(v);
    float f = floor(m);
    uint hi = uint(f);
    // m - f is exact (the fraction of a float), and so is scaling it by 2^32.
    uint lo = uint((m - f) * 4294967296.0);
    if (v < 0.0) negate64(hi, lo);
    uint old = atomicAdd(sums[slot], lo);
    uint carry = (old + lo < old) ? 1u : 0u;   // the low word wrapped
    uint h = hi + carry;
    if (h != 0u) atomicAdd(sums[slot + 1u], h);
}

float read_fixed(uint slot) {
    uint lo = sums[slot], hi = sums[slot + 1u];
    bool negative = int(hi) < 0;
    if (negative) negate64(hi, lo);
    float m = float(hi) + float(lo) * (1.0 / 4294967296.0);
    return negative ? -m : m;
}

#endif

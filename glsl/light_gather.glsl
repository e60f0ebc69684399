// The compute sweep's splat as a tile-binned gather (issue 31): no atomics on the sums.
// sweep_deposit.comp computes each light ray's deposit (light_splat_ray.glsl: the same
// deposit as the point sprites and the atomic compute splat) into `deposits`
// and the bounding box of each block of 8 x 8 neighbouring rays into `blocks`;
// sweep_gather.comp then lets each 8 x 8 tile of pixels find the blocks that overlap it
// and each pixel sum the deposits of their rays. The sum is the atomic splat's: every
// deposit truncated to 32.32 fixed point (light_splat_fixed.glsl) and added as a 64-bit
// integer, here in registers (integer addition is associative: the result does not
// depend on the order, and is bit for bit the atomic splat's).
#ifndef REFRAKT_LIGHT_GATHER_GLSL
#define REFRAKT_LIGHT_GATHER_GLSL

// Per ray r (of the grid, r = j * columns + i): its RayDeposit (light_splat_ray.glsl) in
// DEPOSIT_VEC4S vec4s from 10 r: corner fluxes A, B, footprint (an empty one, zero
// width: no deposit), corners A B, corners C D, direction (xyz), box amplitude, box,
// corner fluxes C, D.
layout(std430, set = 0, binding = 20) buffer Deposits {
    vec4 deposits[];
};
const int DEPOSIT_VEC4S = 10;

void store_deposit(int r, RayDeposit d) {
    int k = DEPOSIT_VEC4S * r;
    deposits[k] = d.flux_a;
    deposits[k + 1] = d.flux_b;
    deposits[k + 2] = d.footprint;
    deposits[k + 3] = d.corners_ab;
    deposits[k + 4] = d.corners_cd;
    deposits[k + 5] = vec4(d.direction, 0.0);
    deposits[k + 6] = d.box_amplitude;
    deposits[k + 7] = d.box;
    deposits[k + 8] = d.flux_c;
    deposits[k + 9] = d.flux_d;
}

vec4 stored_footprint(int r) { return deposits[DEPOSIT_VEC4S * r + 2]; }

RayDeposit load_deposit(int r) {
    int k = DEPOSIT_VEC4S * r;
    RayDeposit d;
    d.flux_a = deposits[k];
    d.flux_b = deposits[k + 1];
    d.footprint = deposits[k + 2];
    d.corners_ab = deposits[k + 3];
    d.corners_cd = deposits[k + 4];
    d.direction = deposits[k + 5].xyz;
    d.box_amplitude = deposits[k + 6];
    d.box = deposits[k + 7];
    d.flux_c = deposits[k + 8];
    d.flux_d = deposits[k + 9];
    return d;
}
// Per block of 8 x 8 rays: the union of its rays' boxes (lo.xy, hi.xy in pixels), empty
// (lo > hi) when none of them carries light.
layout(std430, set = 0, binding = 21) buffer Blocks {
    vec4 blocks[];
};

const int GATHER_BLOCK = 8;   // rays per block side
#define SPLAT_GATHER_CHANNELS 7
// GATHER_LIST (the gather's list of blocks per tile) and GATHER_BUCKETS (the buckets it
// is filled in; a bucket holds at most GATHER_LIST blocks) come from build.rs
// (src/render/limits.rs), which the host checks the ray grid against.
#ifndef GATHER_LIST
#error "GATHER_LIST comes from build.rs (src/render/limits.rs)"
#endif

ivec2 gather_blocks() {
    return (ivec2(P.light_rays.xy) + GATHER_BLOCK - 1) / GATHER_BLOCK;
}

// A 64-bit fixed-point sum in registers: (lo, hi) words as light_splat_fixed.glsl has them.
void add_fixed_reg(inout uvec2 sum, float v) {
    // Branch-free (llvmpipe runs both sides of a branch): 0 adds nothing, a negative
    // value its two's complement.
    float m = abs(v);
    float f = floor(m);
    uint hi = uint(f);
    uint lo = uint((m - f) * 4294967296.0);
    bool negative = v < 0.0;
    uint hi_n = ~hi + (lo == 0u ? 1u : 0u);
    uint lo_n = 0u - lo;
    hi = negative ? hi_n : hi;
    lo = negative ? lo_n : lo;
    uint carry;
    sum.x = uaddCarry(sum.x, lo, carry);
    sum.y = sum.y + hi + carry;
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

#endif

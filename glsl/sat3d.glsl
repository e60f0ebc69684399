// The 3D summed-area table of src/render/sat3d.rs, read side: 64-bit fixed-point sums,
// stored as (low, high) 32-bit words in two's complement (R32G32_UINT), and the box average
// of the field over an axis-aligned box of voxels from eight table texels.
//
// Before including, define (the scan leaves them out: it only needs the arithmetic):
//   SAT3D_LOAD(p)    the table texel at ivec3 p, a uvec2 (e.g. texelFetch(t, p, 0).xy)
//   SAT3D_DIMS       the volume's size in voxels, an ivec3
//   SAT3D_INV_SCALE  Sat3d::inv_scale (1 / the fixed-point scale, a power of two)
//
// Boxes clip at the volume's faces as Schlegel et al.'s extinction-based occlusion treats the
// outside: empty (zero extinction), averaged over the whole box. A box wholly outside is 0.

// a + b modulo 2^64.
uvec2 sat3d_add(uvec2 a, uvec2 b) {
    uint carry;
    uint lo = uaddCarry(a.x, b.x, carry);
    return uvec2(lo, a.y + b.y + carry);
}

// a - b modulo 2^64.
uvec2 sat3d_sub(uvec2 a, uvec2 b) {
    uint borrow;
    uint lo = usubBorrow(a.x, b.x, borrow);
    return uvec2(lo, a.y - b.y - borrow);
}

// The signed 64-bit integer as a float, within 1.5 ulp (the magnitude is converted, so a
// small negative sum does not cancel between its words).
float sat3d_to_float(uvec2 v) {
    bool negative = int(v.y) < 0;
    if (negative) {
        v = sat3d_sub(uvec2(0u), v);
    }
    float m = float(v.y) * 4294967296.0 + float(v.x);
    return negative ? -m : m;
}

#ifdef SAT3D_LOAD
// S at p (inclusive corner), zero where any coordinate is below 0.
uvec2 sat3d_at(ivec3 p) {
    if (any(lessThan(p, ivec3(0)))) {
        return uvec2(0u);
    }
    return SAT3D_LOAD(p);
}

// The exact fixed-point sum over the voxels of [lo, hi] (inclusive) inside the volume.
uvec2 sat3d_box_sum(ivec3 lo, ivec3 hi) {
    ivec3 a = max(lo, ivec3(0)) - 1;
    ivec3 b = min(hi, SAT3D_DIMS - 1);
    if (any(lessThan(b, a + 1))) {
        return uvec2(0u);
    }
    uvec2 s = sat3d_sub(SAT3D_LOAD(b), sat3d_at(ivec3(a.x, b.y, b.z)));
    s = sat3d_sub(s, sat3d_at(ivec3(b.x, a.y, b.z)));
    s = sat3d_sub(s, sat3d_at(ivec3(b.x, b.y, a.z)));
    s = sat3d_add(s, sat3d_at(ivec3(a.x, a.y, b.z)));
    s = sat3d_add(s, sat3d_at(ivec3(a.x, b.y, a.z)));
    s = sat3d_add(s, sat3d_at(ivec3(b.x, a.y, a.z)));
    return sat3d_sub(s, sat3d_at(a));
}

// The field's average over the box [lo, hi] of voxels (inclusive), the outside counting as
// zero over the whole box's volume. Eq. 13 of Ament et al. with C_r(x) = [x - r, x + r].
float sat_box_average(ivec3 lo, ivec3 hi) {
    vec3 size = vec3(max(hi - lo + 1, ivec3(0)));
    float volume = size.x * size.y * size.z;
    if (volume <= 0.0) {
        return 0.0;
    }
    return sat3d_to_float(sat3d_box_sum(lo, hi)) * SAT3D_INV_SCALE / volume;
}
#endif

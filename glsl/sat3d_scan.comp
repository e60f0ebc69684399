#version 460
// The 3D summed-area table of a scalar field (src/render/sat3d.rs), in three passes, one
// per axis (push constant `axis`), each invocation scanning one line sequentially:
//   axis 0: field -> table, along x: the values quantised to fixed point (round(v * scale),
//           scale a power of two, so v * scale is exact) and summed along the line;
//   axis 1: table -> table in place, along y;
//   axis 2: table -> table in place, along z;
// leaving S(x, y, z) = sum over [0, x] x [0, y] x [0, z] of round(v * scale).
// Sums are 64-bit integers in two's complement, (low, high) words, added with carries:
// integer addition is exact and associative, so the table holds exactly the sum of the
// quantised values whatever the order, and box sums from eight corners are exact too.
// The host chooses scale so that no partial sum reaches 2^63 (sat3d.rs).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform sampler3D field;
layout(set = 0, binding = 1, rg32ui) uniform uimage3D table;

layout(push_constant) uniform Push {
    int axis;
    float scale;  // a power of two
    float bound;  // |v| is clamped to it; bound * scale < 2^62 / voxels
} pc;

#include "sat3d.glsl"

// round(v * scale) as a 64-bit integer. Exact: x has 24 significant bits; its split into
// 2^32 * hi + lo is exact in f32 (hi = floor(x / 2^32), lo = x - hi * 2^32 < 2^32 is a
// multiple of ulp(x) with at most 24 bits), and both words convert to uint exactly.
uvec2 quantise(float v) {
    precise float x = roundEven(clamp(v, -pc.bound, pc.bound) * pc.scale);
    precise float a = abs(x);
    precise float hi = floor(a * (1.0 / 4294967296.0));
    precise float lo = a - hi * 4294967296.0;
    uvec2 q = uvec2(uint(lo), uint(hi));
    return x < 0.0 ? sat3d_sub(uvec2(0u), q) : q;
}

void main() {
    ivec3 dims = imageSize(table);
    // The line's two other coordinates; lanes run along the first of them (x for the y and
    // z passes), so neighbouring invocations touch neighbouring texels.
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    int len;
    ivec3 p, step;
    if (pc.axis == 0) {
        if (id.x >= dims.y || id.y >= dims.z) return;
        p = ivec3(0, id.x, id.y);
        step = ivec3(1, 0, 0);
        len = dims.x;
    } else if (pc.axis == 1) {
        if (id.x >= dims.x || id.y >= dims.z) return;
        p = ivec3(id.x, 0, id.y);
        step = ivec3(0, 1, 0);
        len = dims.y;
    } else {
        if (id.x >= dims.x || id.y >= dims.y) return;
        p = ivec3(id.x, id.y, 0);
        step = ivec3(0, 0, 1);
        len = dims.z;
    }
    uvec2 sum = uvec2(0u);
    for (int i = 0; i < len; ++i, p += step) {
        uvec2 v = pc.axis == 0 ? quantise(texelFetch(field, p, 0).x) : imageLoad(table, p).xy;
        sum = sat3d_add(sum, v);
        imageStore(table, p, uvec4(sum, 0u, 0u));
    }
}

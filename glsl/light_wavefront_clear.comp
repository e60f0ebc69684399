#version 460
// The light simulator's clear space (light_wavefront.glsl, `clear_cells`), once per
// simulation, in four dispatches of this shader (CLEAR_PASS):
//   0  each cell's own eta: the range of its eight voxels' values, and the transfer
//      function's eta over that range (it is linear between its samples, ray_tf, so its
//      extremes lie at the samples the range spans): eta if one, else 0; into
//      clear_scratch;
//   1  along x, clear_scratch -> clear_cells; 2 along y, clear_cells -> clear_scratch;
//   3  along z, clear_scratch -> clear_cells: a cell keeps its eta only if every cell
//      within CLEAR_REACH along the axis has the same (non-zero) eta. "All equal" over a
//      box is "all equal" over its rows, so three passes of 9 reads make the 9^3 box.
//
// Why: where one eta holds, the ray equation's path is a line, and a corner's four RK4
// steps of four stages (20 texel fetches and seven transfer-function lookups each) compute
// nothing a line does not. Per cell rather than per brick of value ranges: at 32^3 the
// bricks' 12-voxel neighbourhoods left 0.6 % of the sphere-on-floor scene's patch-cycles
// clear, the cells 2.3 % (docs/NOTES.md, "The light simulator in clear space").
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
#include "light_wavefront.glsl"

layout(constant_id = 2) const int CLEAR_PASS = 0;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    ivec3 n = ivec3(pc.dims.xyz);
    if (any(greaterThanEqual(c, n))) return;
    if (CLEAR_PASS == 0) {
        float lo = 1e30, hi = -1e30;
        for (int k = 0; k < 8; ++k) {
            ivec3 o = ivec3(k & 1, (k >> 1) & 1, k >> 2);
            float v = texelFetch(volume, min(c + o, n - 1), 0).r;
            lo = min(lo, v);
            hi = max(hi, v);
        }
        float last = float(TF_SAMPLES - 1u);
        int j0 = int(floor(clamp(lo, 0.0, 1.0) * last));
        int j1 = int(ceil(clamp(hi, 0.0, 1.0) * last));
        float eta = texelFetch(tf, ivec2(j0, 1), 0).a;
        bool one = true;
        for (int j = j0 + 1; j <= j1; ++j) one = one && texelFetch(tf, ivec2(j, 1), 0).a == eta;
        float scaled = ray_scaled_eta(eta);
        imageStore(clear_scratch, c, vec4(one && scaled > 0.0 ? scaled : 0.0));
        return;
    }
    ivec3 axis = ivec3(CLEAR_PASS == 1, CLEAR_PASS == 2, CLEAR_PASS == 3);
    // Passes 1 and 3 read the scratch image, pass 2 the cells (ping-pong).
    bool from_scratch = CLEAR_PASS != 2;
    float eta = from_scratch ? imageLoad(clear_scratch, c).x : imageLoad(clear_cells, c).x;
    for (int k = -CLEAR_REACH; k <= CLEAR_REACH; ++k) {
        // Cells beyond the volume's edge are clamped to it, as the fetches are.
        ivec3 q = clamp(c + k * axis, ivec3(0), n - 1);
        float e = from_scratch ? imageLoad(clear_scratch, q).x : imageLoad(clear_cells, q).x;
        eta = e == eta ? eta : 0.0;
    }
    if (from_scratch)
        imageStore(clear_cells, c, vec4(eta));
    else
        imageStore(clear_scratch, c, vec4(eta));
}

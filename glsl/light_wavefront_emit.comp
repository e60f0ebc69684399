#version 460
// The light simulator's compaction and expansion, last pass: each patch of the current
// list writes its ku x kv patches (from light_wavefront_step.comp; retired: none, kept:
// one) into the other half of the list at its offset (its block's offset plus its own).
// A split places the new corners on the bilinear patch through the old ones, at
// parameters (a / ku, b / kv), with v interpolated and rescaled to the local eta (|v| =
// eta holds on the ray equation's solutions); each child carries the part of the flux
// and the share its area is of the parent's.
// The interpolated corners are off the true wavefront by the patch's curvature over its
// size (second order); the emit is where the wavefront is refined (sect. 4.2.3).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "light_wavefront.glsl"
#include "light_splat_fixed.glsl"

vec3 corner_mix(vec4 c[4], vec2 t) {
    return mix(mix(c[0].xyz, c[1].xyz, t.x), mix(c[3].xyz, c[2].xyz, t.x), t.y);
}

// The area of child (a, b) of the patch with corners c split at parameters `inv` apart:
// half the length of its diagonals' cross product (either orientation).
float child_area(vec4 c[4], uint a, uint b, vec2 inv) {
    vec3 x0 = corner_mix(c, vec2(a, b) * inv);
    vec3 x1 = corner_mix(c, vec2(a + 1u, b) * inv);
    vec3 x2 = corner_mix(c, vec2(a + 1u, b + 1u) * inv);
    vec3 x3 = corner_mix(c, vec2(a, b + 1u) * inv);
    return 0.5 * length(cross(x2 - x0, x3 - x1));
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = control[CTRL_COUNT + pc.parity];
    if (i >= count) return;
    Patch p = patches[i];
    uint code = uint(p.x[3].w);
    if (code == 0u) return;
    uint ku = code & 7u, kv = code >> 3u;
    uint offset = counts[i] + block_sums[i / WAVEFRONT_GROUP];
    vec2 inv = 1.0 / vec2(ku, kv);
    // The parent's irradiance is uniform over it (the patch is the wavefront's
    // discretisation): each child takes the flux of the area it covers, not an equal
    // part (equal parts of a trapezoid's children put +-2.3 % stripes on the light of a
    // point source, whose gnomonic patches are trapezoids; measured).
    float total = 0.0;
    for (uint b = 0u; b < kv; ++b)
        for (uint a = 0u; a < ku; ++a) total += child_area(p.x, a, b, inv);
    for (uint b = 0u; b < kv; ++b) {
        for (uint a = 0u; a < ku; ++a) {
            uint o = offset + b * ku + a;
            float part = total > 0.0 ? child_area(p.x, a, b, inv) / total
                                     : 1.0 / float(ku * kv);
            if (o >= pc.capacity) {
                // Dropped: the host refuses the simulation (CTRL_NEEDED says by how much).
                vec3 f = p.flux.rgb * part;
                for (uint c = 0u; c < 3u; ++c) {
                    uvec2 w = to_fixed(f[c]);
                    uint slot = CTRL_DROPPED + 2u * c;
                    uint old = atomicAdd(control[slot], w.x);
                    uint h = w.y + (old + w.x < old ? 1u : 0u);
                    if (h != 0u) atomicAdd(control[slot + 1u], h);
                }
                continue;
            }
            Patch q = p;
            if (ku * kv > 1u) {
                vec2 params[4] = vec2[4](vec2(a, b), vec2(a + 1u, b), vec2(a + 1u, b + 1u),
                                         vec2(a, b + 1u));
                for (int c = 0; c < 4; ++c) {
                    vec2 t = params[c] * inv;
                    vec3 x = corner_mix(p.x, t);
                    vec3 v = corner_mix(p.v, t);
                    q.x[c].xyz = x;
                    q.v[c].xyz = normalize(v) * ray_eta(x);
                }
                q.flux.rgb = p.flux.rgb * part;
                q.x[0].w = p.x[0].w * part;
                q.x[1].w = p.x[1].w + 1.0;
            }
            patches_next[o] = q;
        }
    }
}

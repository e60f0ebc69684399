#version 460
// The light simulator's patch update (seed 001 sect. 5.2.1), its deposits (5.2.2) and its
// tessellation analysis (5.2.3), one invocation per patch of the current list: advance
// the four corners `substeps` equi-temporal RK4 steps, attenuate the flux by the corners'
// mean optical depth (eq. 18), count the flux crossing each receiver plane over the area
// the patch spans there, deposit it into the fluence volume, then classify the patch.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "light_wavefront.glsl"
#include "light_splat_fixed.glsl"
#include "triangle_coverage.glsl"

// Add v (|v| < 2^31) to the 32.32 sum at words (slot, slot + 1) of buffer `buf`.
#define ADD_FIXED(buf, slot, v) \
    { \
        float v_ = (v); \
        if (v_ != 0.0) { \
            uvec2 w_ = to_fixed(v_); \
            uint old_ = atomicAdd(buf[slot], w_.x); \
            uint h_ = w_.y + (old_ + w_.x < old_ ? 1u : 0u); \
            if (h_ != 0u) atomicAdd(buf[(slot) + 1u], h_); \
        } \
    }

void add_control_rgb(uint at, vec3 f) {
    for (uint c = 0u; c < 3u; ++c) ADD_FIXED(control, at + 2u * c, f[c]);
}

// A receiver's widest patch footprint covered exactly, pixels per side; wider ones (a
// patch not yet tessellated, grazing the plane) put their flux in the pixel under their
// centre and are counted (CTRL_COARSE).
const int MAX_FOOTPRINT = 12;

// The flux `f` of the patch whose corners cross receiver r at q[0..3] (pixels), spread
// over the two triangles (0, 1, 2) and (0, 2, 3) with a uniform density (the patch's
// irradiance), each pixel taking its exact share (triangle_weights).
void deposit_on_receiver(uint r, vec2 q[4], vec3 f) {
    vec4 o = receivers[4u * r];
    vec4 u = receivers[4u * r + 1u];
    vec4 vv = receivers[4u * r + 2u];
    int w = int(o.w), h = int(u.w);
    uint base = uint(vv.w);  // this receiver's first slot: 3 x the pixels before it
    uint pixels = uint(w * h);
    float a1 = abs(cross2(q[1] - q[0], q[2] - q[0]));
    float a2 = abs(cross2(q[2] - q[0], q[3] - q[0]));
    float total = a1 + a2;
    // Shares of the flux by area; a patch of no area (a perfect focus) splits it evenly.
    float s1 = total > 0.0 ? a1 / total : 0.5;
    vec2 lo = floor(min(min(q[0], q[1]), min(q[2], q[3])));
    vec2 hi = floor(max(max(q[0], q[1]), max(q[2], q[3])));
    if (any(greaterThan(hi - lo, vec2(float(MAX_FOOTPRINT - 1))))) {
        ivec2 p = ivec2(floor(0.25 * (q[0] + q[1] + q[2] + q[3])));
        if (all(greaterThanEqual(p, ivec2(0))) && all(lessThan(p, ivec2(w, h)))) {
            uint px = uint(p.y * w + p.x);
            for (uint c = 0u; c < 3u; ++c)
                ADD_FIXED(receiver_sums, 2u * (base + c * pixels + px), f[c]);
        }
        atomicAdd(control[CTRL_COARSE], 1u);
        return;
    }
    ivec2 l = max(ivec2(lo), ivec2(0)), m = min(ivec2(hi), ivec2(w - 1, h - 1));
    for (int y = l.y; y <= m.y; ++y) {
        for (int x = l.x; x <= m.x; ++x) {
            vec2 p = vec2(x, y);
            vec3 t1 = triangle_weights(q[0], q[1], q[2], p);
            vec3 t2 = triangle_weights(q[0], q[2], q[3], p);
            // Each weight sums to 1/3 over the triangle: the three make its fraction.
            float share = s1 * (t1.x + t1.y + t1.z) + (1.0 - s1) * (t2.x + t2.y + t2.z);
            if (share <= 0.0) continue;
            uint px = uint(y * w + x);
            for (uint c = 0u; c < 3u; ++c)
                ADD_FIXED(receiver_sums, 2u * (base + c * pixels + px), f[c] * share);
        }
    }
}

// World point p in the fluence volume's voxel coordinates (voxel centres at integers).
vec3 fluence_grid(vec3 p) {
    return (p / (2.0 * pc.half_extent.xyz) + 0.5) * pc.dims.xyz - 0.5;
}

// The fluence deposits of a patch's four points p0..p3 (each its amount, rgb, trilinearly
// into the fluence volume, and the direction dir weighted by its luminance), merged where
// points share a trilinear cell: their weights on the cell's eight voxels are summed
// before the atomic adds, so a cell shared by all four costs 48 adds, not 192. Points
// of a patch lie within about a voxel of each other and often share their cell; the
// loop runs once per distinct cell (llvmpipe leaves a loop once all its lanes have).
// The sums are the same to 2^-32 per add (the fixed point is truncated once per voxel
// and channel instead of once per point).
void deposit_fluence4(vec3 p0, vec3 p1, vec3 p2, vec3 p3, vec3 a0, vec3 a1, vec3 a2,
                      vec3 a3, vec3 dir) {
    vec3 g0 = fluence_grid(p0), g1 = fluence_grid(p1), g2 = fluence_grid(p2), g3 = fluence_grid(p3);
    vec3 b0 = floor(g0), b1 = floor(g1), b2 = floor(g2), b3 = floor(g3);
    vec3 f0 = g0 - b0, f1 = g1 - b1, f2 = g2 - b2, f3 = g3 - b3;
    const vec3 LUM = vec3(0.2126, 0.7152, 0.0722);
    float l0 = dot(a0, LUM), l1 = dot(a1, LUM), l2 = dot(a2, LUM), l3 = dot(a3, LUM);
    ivec3 d = ivec3(pc.dims.xyz);
    uint voxels = uint(d.x * d.y * d.z);
    uint todo = 15u;
    while (todo != 0u) {
        int lead = findLSB(todo);
        vec3 b = lead == 0 ? b0 : (lead == 1 ? b1 : (lead == 2 ? b2 : b3));
        // The lead always takes its own point (a NaN cell equals nothing, not even
        // itself: the loop would never end).
        bool m0 = (todo & 1u) != 0u && (lead == 0 || b0 == b);
        bool m1 = (todo & 2u) != 0u && (lead == 1 || b1 == b);
        bool m2 = (todo & 4u) != 0u && (lead == 2 || b2 == b);
        bool m3 = (todo & 8u) != 0u && (lead == 3 || b3 == b);
        todo &= ~((m0 ? 1u : 0u) | (m1 ? 2u : 0u) | (m2 ? 4u : 0u) | (m3 ? 8u : 0u));
        for (int k = 0; k < 8; ++k) {
            vec3 o = vec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
            ivec3 c = ivec3(b) + ivec3(o);
            if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, d))) continue;
            vec3 v0 = mix(1.0 - f0, f0, o), v1 = mix(1.0 - f1, f1, o);
            vec3 v2 = mix(1.0 - f2, f2, o), v3 = mix(1.0 - f3, f3, o);
            float w0 = m0 ? v0.x * v0.y * v0.z : 0.0, w1 = m1 ? v1.x * v1.y * v1.z : 0.0;
            float w2 = m2 ? v2.x * v2.y * v2.z : 0.0, w3 = m3 ? v3.x * v3.y * v3.z : 0.0;
            vec3 rgb = w0 * a0 + w1 * a1 + w2 * a2 + w3 * a3;
            vec3 dl = dir * (w0 * l0 + w1 * l1 + w2 * l2 + w3 * l3);
            uint vox = uint((c.z * d.y + c.y) * d.x + c.x);
            ADD_FIXED(fluence_sums, 2u * vox, rgb.r);
            ADD_FIXED(fluence_sums, 2u * (voxels + vox), rgb.g);
            ADD_FIXED(fluence_sums, 2u * (2u * voxels + vox), rgb.b);
            ADD_FIXED(fluence_sums, 2u * (3u * voxels + vox), dl.x);
            ADD_FIXED(fluence_sums, 2u * (4u * voxels + vox), dl.y);
            ADD_FIXED(fluence_sums, 2u * (5u * voxels + vox), dl.z);
        }
    }
}

// Where corner k's step from a to b meets the plane n . x = c: on its chord, linearly (the
// corners cross at slightly different times; extrapolated where one has not reached it).
vec3 on_plane(vec3 a, vec3 b, vec3 n, float c) {
    float da = dot(n, a) - c, db = dot(n, b) - c;
    float t = db != da ? da / (da - db) : 0.0;
    return mix(a, b, t);
}

// v after a step brought back to |v| = eta at x (the ray equation's invariant) by
// changing it only along the step's kick dv, the direction of the gradients it met: a
// face or the box's own boundary kicks a ray along its normal, and what is conserved
// across it is the rest of v (Snell's law: eta sin(theta) along the face). A fixed step
// whose RK4 stages straddle a step of eta thinner than the step (the box's boundary
// where the volume's edge voxels are not eta 1, a film) gets a kick of the wrong size:
// the light then entered a prism with |v| 6 % over eta and left its 30-degree face 4.8
// degrees short of Snell's deviation, a different error at each step size (32³, a
// 3-voxel face whose ramp reaches the box's face; docs/NOTES.md). Where the step met no
// gradient, or no such v exists, the direction is kept and |v| set to eta.
vec3 on_shell(vec3 v, vec3 dv, vec3 x) {
    float eta = ray_eta(x);
    float kick = length(dv);
    if (kick > 1e-6 * eta) {
        vec3 n = dv / kick;
        float vn = dot(v, n);
        vec3 vt = v - vn * n;
        float across = eta * eta - dot(vt, vt);
        if (across > 0.0) return vt + (vn >= 0.0 ? 1.0 : -1.0) * sqrt(across) * n;
    }
    return normalize(v) * eta;
}

vec3 bilinear(vec3 a, vec3 b, vec3 c, vec3 d, vec2 t) {
    return mix(mix(a, b, t.x), mix(d, c, t.x), t.y);
}

// The refractive index of corner x's whole cycle when one eta holds everywhere the cycle
// can reach, so the ray equation's path is a line (grad eta = 0 in eqs. 14-15); 0 where
// it may turn. In one medium v = eta dx/ds is constant and the cycle moves the corner
// along dx/dt = v / eta^2 (eq. 14) by dt substeps |v| / eta^2. Inside the box: at most 3
// voxels along each axis keeps every cell its RK4 stages and differences would read
// within CLEAR_REACH of its start's (light_wavefront.glsl), and both ends at least 0.1
// voxel inside keeps them from reading the outside's value 0 (the cells leave it out).
// Outside: both ends at least 0.1 voxel beyond one face (the box is convex) read only
// the value 0 (launched light on its way in, light on its way out).
float straight_cycle(vec3 x, vec3 v) {
    if (!WAVEFRONT_CLEAR) return 0.0;
    vec3 n = pc.dims.xyz;
    vec3 u = ray_tex(x) * n;  // voxels
    vec3 lo = vec3(0.1), hi = n - 0.1;
    bool starts_inside = all(greaterThanEqual(u, lo)) && all(lessThanEqual(u, hi));
    ivec3 cell = clamp(ivec3(floor(u - 0.5)), ivec3(0), ivec3(n) - 1);
    float eta = starts_inside ? imageLoad(clear_cells, cell).x : ray_eta_of(0.0, vec3(-1.0));
    vec3 voxel = 2.0 * pc.half_extent.xyz / n;
    vec3 move = v * (pc.dt * float(pc.substeps) / max(eta * eta, 1e-6)) / voxel;
    vec3 end = u + move;
    bool inside = starts_inside && all(greaterThanEqual(end, lo)) && all(lessThanEqual(end, hi)) &&
                  all(lessThanEqual(abs(move), vec3(3.0)));
    vec3 a = min(u, end), b = max(u, end);
    bool outside = any(lessThan(b, -lo)) || any(greaterThan(a, n + lo));
    return eta > 0.0 && (inside || outside) ? eta : 0.0;
}

// After the corners' substep from x0 to p.x across optical depths summing to tau: dim the
// flux (eq. 18), count it on the receivers its centre crossed, deposit it into the
// fluence volume.
void deposit_substep(inout Patch p, vec3 x0[4], vec3 tau, inout vec3 flux, inout uint reached) {
    float ref = pc.half_extent.w;
    // Eq. 18 over the step: the corners' mean optical depth (the patch's light is
    // dimmed as the medium it sweeps, to first order in its size).
    vec3 before = flux;
    flux *= exp(-0.25 * tau);
    vec3 flux_mid = 0.5 * (before + flux);
    for (uint r = 0u; r < pc.receiver_count; ++r) {
        vec4 n = receivers[4u * r + 3u];
        vec3 c0 = 0.25 * (x0[0] + x0[1] + x0[2] + x0[3]);
        vec3 c1 = 0.25 * (p.x[0].xyz + p.x[1].xyz + p.x[2].xyz + p.x[3].xyz);
        float d0 = dot(n.xyz, c0) - n.w, d1 = dot(n.xyz, c1) - n.w;
        if ((reached & (1u << r)) != 0u || d1 < 0.0) continue;
        reached |= 1u << r;
        vec4 o = receivers[4u * r];
        vec3 u = receivers[4u * r + 1u].xyz, vv = receivers[4u * r + 2u].xyz;
        vec2 q[4];
        for (int k = 0; k < 4; ++k) {
            vec3 w = on_plane(x0[k], p.x[k].xyz, n.xyz, n.w) - o.xyz;
            q[k] = vec2(dot(w, u) / dot(u, u), dot(w, vv) / dot(vv, vv));
        }
        // The flux where the centre crosses, in the light's irradiance times pixel
        // areas: the sums then read as irradiance per pixel.
        float t = d0 < 0.0 ? d0 / (d0 - d1) : 0.0;
        vec3 f = mix(before, flux, t) * (ref * ref) / length(cross(u, vv));
        deposit_on_receiver(r, q, f);
    }
    if (WAVEFRONT_FLUENCE) {
        // Flux x path length / voxel volume at four points of the patch (its quarters'
        // centres), half way along the step: the irradiance its stream tube brings
        // to the voxels it sweeps.
        vec3 vox = 2.0 * pc.half_extent.xyz / pc.dims.xyz;
        float volume = vox.x * vox.y * vox.z;
        vec3 dir = normalize(p.v[0].xyz + p.v[1].xyz + p.v[2].xyz + p.v[3].xyz);
        vec3 at[4], amount[4];
        for (int k = 0; k < 4; ++k) {
            vec2 t = vec2((k & 1) == 0 ? 0.25 : 0.75, (k & 2) == 0 ? 0.25 : 0.75);
            vec3 a = bilinear(x0[0], x0[1], x0[2], x0[3], t);
            vec3 b = bilinear(p.x[0].xyz, p.x[1].xyz, p.x[2].xyz, p.x[3].xyz, t);
            amount[k] = 0.25 * flux_mid * (ref * ref) * length(b - a) / volume;
            at[k] = 0.5 * (a + b);
        }
        deposit_fluence4(at[0], at[1], at[2], at[3], amount[0], amount[1], amount[2],
                         amount[3], dir);
    }
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = control[CTRL_COUNT + pc.parity];
    if (i >= count) return;
    Patch p = patches[i];
    float ref = pc.half_extent.w;
    // Launched patches (x[3].w < 0) carry unit directions: v = eta dx/ds starts at the
    // local eta (the ray equation keeps |v| = eta from there).
    // The receivers a patch has reached (v[1].w, a bit mask below 2^24: exact as a
    // float). A receiver counts a patch's flux once, when its centre first lies beyond
    // the plane: children inherit the mask, so a split patch straddling a plane (some
    // children's centres on each side) is counted neither twice nor never.
    uint reached = uint(p.v[1].w);
    if (p.x[3].w < 0.0) {
        for (int k = 0; k < 4; ++k) p.v[k].xyz = normalize(p.v[k].xyz) * ray_eta(p.x[k].xyz);
        // A plane the light starts beyond is one it never reaches.
        vec3 c = 0.25 * (p.x[0].xyz + p.x[1].xyz + p.x[2].xyz + p.x[3].xyz);
        for (uint r = 0u; r < pc.receiver_count; ++r) {
            vec4 n = receivers[4u * r + 3u];
            if (dot(n.xyz, c) - n.w >= 0.0) reached |= 1u << r;
        }
    }
    vec3 flux = p.flux.rgb;
    // Whether every corner's cycle runs straight (straight_cycle): then the substeps below
    // move the corners along lines, and otherwise by the ray equation. Loops' trip counts,
    // not a branch: llvmpipe runs both sides of a branch but leaves a loop once all its
    // lanes are done (and neighbouring patches cross the same space). One test per patch
    // and no loop nested in the substeps': a loop of 0 or 1 integrations per corner made
    // the whole simulation 1.5 x slower on llvmpipe even where it always integrated.
    float eta[4];
    for (int k = 0; k < 4; ++k) eta[k] = straight_cycle(p.x[k].xyz, p.v[k].xyz);
    bool lines = eta[0] > 0.0 && eta[1] > 0.0 && eta[2] > 0.0 && eta[3] > 0.0;
    uint curved = lines ? 0u : pc.substeps;
    if (lines) atomicAdd(control[CTRL_STRAIGHT], 1u);
    for (uint s = 0u; s < curved; ++s) {
        vec3 x0[4];
        vec3 tau = vec3(0.0);
        for (int k = 0; k < 4; ++k) {
            vec3 x = p.x[k].xyz, v = p.v[k].xyz;
            x0[k] = x;
            vec3 v_before = v;
            ray_rk4_temporal(x, v, pc.dt);
            v = on_shell(v, v - v_before, x);
            tau += ray_optical_depth(x0[k], x, length(x - x0[k]));
            p.x[k].xyz = x;
            p.v[k].xyz = v;
        }
        deposit_substep(p, x0, tau, flux, reached);
    }
    for (uint s = curved; s < pc.substeps; ++s) {
        vec3 x0[4];
        vec3 tau = vec3(0.0);
        for (int k = 0; k < 4; ++k) {
            // With one eta v is constant: dx/dt = v / eta^2 (eq. 14). The medium may
            // still dim the light unevenly (an opaque floor's skin): its optical depth is
            // taken along the line as along the ray equation's chord.
            vec3 x = p.x[k].xyz;
            x0[k] = x;
            x = x + (pc.dt / (eta[k] * eta[k])) * p.v[k].xyz;
            tau += ray_optical_depth(x0[k], x, length(x - x0[k]));
            p.x[k].xyz = x;
        }
        deposit_substep(p, x0, tau, flux, reached);
    }
    p.flux.rgb = flux;
    p.v[1].w = float(reached);

    // Tessellation analysis (sect. 5.2.3).
    vec3 e0 = p.x[1].xyz - p.x[0].xyz, e1 = p.x[2].xyz - p.x[1].xyz;
    vec3 e2 = p.x[3].xyz - p.x[2].xyz, e3 = p.x[0].xyz - p.x[3].xyz;
    // The longest edge along each of the patch's two parameters (u: edges 0-1 and 3-2;
    // v: edges 1-2 and 0-3), in reference steps: a patch is split along each as often
    // as that edge needs, so a needle-thin patch near a caustic splits along its
    // length alone (k x k children would cost k² patches where one edge alone is long).
    float span_u = max(length(e0), length(e2)) / ref;
    float span_v = max(length(e1), length(e3)) / ref;
    float span = max(span_u, span_v);
    vec3 mean_v = p.v[0].xyz + p.v[1].xyz + p.v[2].xyz + p.v[3].xyz;
    // The oriented area along the light: its sign turns where the patch crossed a focus.
    float oriented = dot(cross(p.x[2].xyz - p.x[0].xyz, p.x[3].xyz - p.x[1].xyz), mean_v);
    float sign_now = oriented >= 0.0 ? 1.0 : -1.0;
    bool crossed = sign_now != p.x[2].w;
    p.x[2].w = sign_now;
    vec3 share = p.x[0].w * pc.colour.rgb;
    float transmitted = 0.0;
    for (int c = 0; c < 3; ++c)
        transmitted = max(transmitted, share[c] > 0.0 ? flux[c] / share[c] : 0.0);
    bool outside = true;
    for (int k = 0; k < 4; ++k) {
        vec3 x = p.x[k].xyz, v = p.v[k].xyz;
        bvec3 beyond = greaterThan(abs(x), pc.half_extent.xyz);
        bvec3 away = greaterThan(x * v, vec3(0.0));
        outside = outside && any(bvec3(beyond.x && away.x, beyond.y && away.y, beyond.z && away.z));
    }
    uint ku = 1u, kv = 1u;
    bool keep = true;
    if (crossed) {
        atomicAdd(control[CTRL_FOCI], 1u);
        add_control_rgb(CTRL_AT_FOCI, flux);
        p.v[0].w += 1.0;
    }
    if (outside) {
        keep = false;
        add_control_rgb(CTRL_LEFT, flux);
    } else if (crossed && pc.discard_at_foci == 1u) {
        keep = false;
    } else if (transmitted < pc.colour.w) {
        keep = false;
        add_control_rgb(CTRL_ABSORBED, flux);
    } else if (p.x[0].w < pc.min_dilution * p.v[2].w) {
        // Split down to a tiny part of its launched patch (the paper's energy threshold,
        // sect. 5.2.3): light fanned out so far (beside a silhouette, after a micro-focus)
        // that following it would multiply the list every cycle for little flux.
        keep = false;
        add_control_rgb(CTRL_DILUTED, flux);
    } else if (span > pc.tear_span) {
        // Torn: at most a voxel a cycle ago and now many apart, its corners went
        // different ways (either side of a silhouette, or one trapped by total
        // reflection): the wavefront between them is not this patch, and splitting it
        // would place patches where no light goes, and multiply them every cycle.
        keep = false;
        add_control_rgb(CTRL_TORN, flux);
    } else if (span > 1.0) {
        if (uint(p.x[1].w) < pc.max_level) {
            ku = clamp(uint(ceil(span_u)), 1u, 4u);
            kv = clamp(uint(ceil(span_v)), 1u, 4u);
        } else {
            atomicAdd(control[CTRL_UNSPLIT], 1u);
        }
    }
    if (keep) {
        float worst = max(span_u / float(ku), span_v / float(kv));
        atomicMax(control[CTRL_WORST_SPAN], floatBitsToUint(worst));
    }
    // Children per side for the emit: ku + 8 kv (0: retired).
    p.x[3].w = keep ? float(ku + 8u * kv) : 0.0;
    counts[i] = keep ? ku * kv : 0u;
    patches[i] = p;
}

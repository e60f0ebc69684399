#version 460
// Builds the preintegration table (thesis sect. 4.3 "Compositing", 5.1): for every pair of
// front/back scalar values, the segment's premultiplied particle colour + opacity
// (eqs. 3.17, 4.16) in layer 0 and its medium colour as a multiplicative integral
// (eqs. 4.14-4.15) in layer 1, for a segment one reference sample distance long.
//
// As in the thesis: 256 samples between the two values, composited front to back with
// opacity corrected for 1/256 of the segment. Two numerical choices, both exact
// rewrites of that compositing, keep the table within 1e-3 of the continuous integrals:
//  * the transfer functions are evaluated from their control points, not from the
//    sampled 1D texture, so steps (two control points at one s) stay sharp;
//  * transmittance and medium are accumulated as logarithms (optical depth
//    tau = sum of -ln(1 - alpha)/256, ln M = sum of ln(m)/256) and exponentiated, instead
//    of multiplying 256 rounded factors: 1 - A = exp(-tau) is eq. 3.7 exactly.
//  * the optical depth and ln(m) of each of the 256 sub-segments are averaged over
//    SUB points inside it, so a step in a function that falls inside a sub-segment is
//    weighted by where it falls (a single midpoint sample is off by up to half a
//    sub-segment: 2e-3 for a step from m = 1 to 0.3, measured);
// The colour sample sits at the sub-segment's midpoint, and its particles see the medium
// up to the middle of their own sub-segment.
//
// Layer 2 is not an integral: the extremes of eta over the values between front and
// back, (largest eta, the value where it peaks, smallest eta, the value of that dip). The
// sweep uses it to find films of glass that a value ramp crosses between two samples
// (sweep_plane.glsl, "films"). For a plateau the value is its middle.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

// Control points, see transfer::TransferFunctions::control_points(): for function f
// (0 colour, 1 opacity, 2 medium, 3 eta) points[offset[f] .. offset[f] + count[f]] hold
// (s, value.xyz) sorted by s.
layout(set = 0, binding = 0, std430) readonly buffer ControlPoints {
    uvec4 count;
    uvec4 offset;
    vec4 points[];
} tf;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2DArray table;

// A label volume (src/labels.rs) is sampled at the nearest voxel: between two samples the
// value does not pass through the values between (other labels, or none) but jumps from
// the front sample's label to the back one's. The segment is then half the front label
// and half the back label, and η's extremes are those of the two labels.
layout(constant_id = 0) const bool LABELS = false;

const uint STEPS = 256u;
const uint SUB = 8u;
const float MIN_TRANSMITTANCE = 1e-30;  // ln() stays finite for alpha = 1 or m = 0

// Piecewise-linear evaluation, right-continuous at steps, constant outside the points.
// `cursor` is the index of the last point with position <= s (-1 if none). Along one
// segment s moves monotonically, so the cursor only walks forward (or backward): O(1) per
// evaluation instead of a search.
int locate(uint f, float s) {
    uint off = tf.offset[f];
    int n = int(tf.count[f]);
    int lo = 0, hi = n;  // first point with position > s
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (tf.points[off + uint(mid)].x <= s) lo = mid + 1; else hi = mid;
    }
    return lo - 1;
}

void advance(uint f, float s, inout int cursor) {
    uint off = tf.offset[f];
    int n = int(tf.count[f]);
    while (cursor + 1 < n && tf.points[off + uint(cursor + 1)].x <= s) cursor++;
    while (cursor >= 0 && tf.points[off + uint(cursor)].x > s) cursor--;
}

vec3 eval_tf(uint f, float s, inout int cursor) {
    uint off = tf.offset[f];
    int n = int(tf.count[f]);
    advance(f, s, cursor);
    if (cursor < 0) return tf.points[off].yzw;
    if (cursor + 1 >= n) return tf.points[off + uint(n - 1)].yzw;
    vec4 a = tf.points[off + uint(cursor)];
    vec4 b = tf.points[off + uint(cursor + 1)];
    float t = b.x > a.x ? (s - a.x) / (b.x - a.x) : 1.0;
    return mix(a.yzw, b.yzw, t);
}

// Largest (sign 1) or smallest (sign -1) eta over [lo, hi] and the middle of where it
// is attained. eta is piecewise linear, so its extremes lie at the interval's ends or at
// control points inside it.
vec2 eta_extreme(float lo, float hi, float sign) {
    uint off = tf.offset[3];
    int n = int(tf.count[3]);
    if (n == 0) return vec2(1.0, 0.5 * (lo + hi));   // no eta function: vacuum
    int cursor = locate(3u, lo);
    float best = sign * eval_tf(3u, lo, cursor).x;
    float first = lo, last = lo;
    for (int k = 0; k <= n; ++k) {
        // The control points strictly inside (lo, hi), then hi itself.
        float s = k < n ? tf.points[off + uint(k)].x : hi;
        if (k < n && !(s > lo && s < hi)) continue;
        float e = sign * (k < n ? tf.points[off + uint(k)].y : eval_tf(3u, hi, cursor).x);
        if (e > best + 1e-6) {
            best = e;
            first = s;
            last = s;
        } else if (e >= best - 1e-6) {
            last = s;
        }
    }
    return vec2(sign * best, 0.5 * (first + last));
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, uvec2(PREINT_SIZE)))) return;
    float front = float(id.x) / float(PREINT_SIZE - 1u);
    float back = float(id.y) / float(PREINT_SIZE - 1u);
    float h = 1.0 / float(STEPS);

    int cur_c = locate(0u, front), cur_a = locate(1u, front), cur_m = locate(2u, front);
    vec3 C = vec3(0.0);
    float tau = 0.0;          // optical depth so far
    vec3 ln_m = vec3(0.0);    // log of the medium product so far
    for (uint k = 0u; k < STEPS; ++k) {
        float s = LABELS ? (2u * k < STEPS ? front : back) : mix(front, back, (float(k) + 0.5) * h);
        vec3 colour = eval_tf(0u, s, cur_c);
        // Where the sub-segment contains no control point of opacity or medium both are
        // linear across it and one midpoint sample suffices; where it does, SUB samples
        // place the kink or step.
        float s_end = LABELS ? s : mix(front, back, float(k + 1u) * h);
        int end_a = cur_a, end_m = cur_m;
        advance(1u, s_end, end_a);
        advance(2u, s_end, end_m);
        uint sub = (end_a == cur_a && end_m == cur_m) ? 1u : SUB;
        float sigma_h = 0.0;
        vec3 ln_m_h = vec3(0.0);
        for (uint j = 0u; j < sub; ++j) {
            float sj = LABELS ? s : mix(front, back, (float(k) + (float(j) + 0.5) / float(sub)) * h);
            int ca = cur_a, cm = cur_m;
            float alpha = eval_tf(1u, sj, ca).x;
            vec3 m = eval_tf(2u, sj, cm);
            sigma_h -= log(max(1.0 - alpha, MIN_TRANSMITTANCE));
            ln_m_h += log(max(m, vec3(MIN_TRANSMITTANCE)));
        }
        cur_a = end_a;
        cur_m = end_m;
        sigma_h *= h / float(sub);
        ln_m_h *= h / float(sub);
        // (1 - A) * alpha' of the compositing = T_before - T_after.
        float absorbed = exp(-tau) - exp(-(tau + sigma_h));
        // Oddy-Willis: particle light is filtered by the medium in front of it (eq. 4.16).
        C += absorbed * exp(ln_m + 0.5 * ln_m_h) * colour;
        tau += sigma_h;
        ln_m += ln_m_h;
    }
    imageStore(table, ivec3(id, 0), vec4(C, 1.0 - exp(-tau)));
    imageStore(table, ivec3(id, 1), vec4(exp(ln_m), 1.0));
    float lo = min(front, back), hi = max(front, back);
    if (LABELS) {
        int c = locate(3u, front);
        float ef = tf.count[3] == 0u ? 1.0 : eval_tf(3u, front, c).x;
        c = locate(3u, back);
        float eb = tf.count[3] == 0u ? 1.0 : eval_tf(3u, back, c).x;
        vec2 top = ef >= eb ? vec2(ef, front) : vec2(eb, back);
        vec2 dip = ef <= eb ? vec2(ef, front) : vec2(eb, back);
        imageStore(table, ivec3(id, 2), vec4(top, dip));
    } else {
        imageStore(table, ivec3(id, 2), vec4(eta_extreme(lo, hi, 1.0), eta_extreme(lo, hi, -1.0)));
    }
}

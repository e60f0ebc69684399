#version 460
// Builds the preintegration table (thesis sect. 4.3 "Compositing", 5.1): for every pair of
// front/back scalar values, the segment's premultiplied particle colour + opacity
// (eqs. 3.17, 4.16) in layer 0 and its medium colour as a multiplicative integral
// (eqs. 4.14-4.15) in layer 1, for a segment of one reference sample distance.
// Computed as the thesis does: 256 samples between the two values, composited front to
// back with opacity corrected for 1/256 of the segment. Samples sit at the midpoints of
// the 256 sub-segments, which makes the sum a midpoint rule (second-order accurate).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(set = 0, binding = 0) uniform sampler1DArray tf;  // layer 0: colour, opacity; 1: medium, eta
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2DArray table;

const uint STEPS = 256u;

// Exact piecewise-linear reconstruction of the sampled TF (texelFetch + manual lerp), so
// the table does not depend on the sampler's sub-texel precision.
vec4 fetch_tf(float s, int layer) {
    float x = clamp(s, 0.0, 1.0) * float(TF_SAMPLES - 1u);
    int i = min(int(floor(x)), int(TF_SAMPLES) - 2);
    float t = x - float(i);
    vec4 a = texelFetch(tf, ivec2(i, layer), 0);
    vec4 b = texelFetch(tf, ivec2(i + 1, layer), 0);
    return mix(a, b, t);
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, uvec2(PREINT_SIZE)))) return;
    float front = float(id.x) / float(PREINT_SIZE - 1u);
    float back = float(id.y) / float(PREINT_SIZE - 1u);
    float ratio = 1.0 / float(STEPS);

    vec3 C = vec3(0.0);
    float A = 0.0;
    vec3 M = vec3(1.0);
    for (uint k = 0u; k < STEPS; ++k) {
        float s = mix(front, back, (float(k) + 0.5) * ratio);
        vec4 ca = fetch_tf(s, 0);
        vec3 m = fetch_tf(s, 1).rgb;
        float a = correct_opacity(ca.a, ratio);
        vec3 half_m = correct_medium(m, 0.5 * ratio);
        // Oddy-Willis: particle light is filtered by the medium in front of it (eq. 4.16).
        // The sample's particles sit, on average, half a sub-step deep into its own medium.
        C += (1.0 - A) * M * half_m * ca.rgb * a;
        A += (1.0 - A) * a;
        M *= half_m * half_m;
    }
    imageStore(table, ivec3(id, 0), vec4(C, A));
    imageStore(table, ivec3(id, 1), vec4(M, 1.0));
}

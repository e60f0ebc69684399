// The ambient-scattering model's preintegrated tables (render/ambient/table/), read side:
// node-centred axes, so texel i of an axis of n nodes sits at texture coordinate
// (i + 0.5) / n and linear filtering interpolates between nodes:
//   theta_i = pi i / (n_theta - 1),  s_k = (1 + s_max)^(k / (n_s - 1)) - 1,
//   g_m = -0.99 + 1.98 m / (n_g - 1)
// (s = r * ambient extinction, dimensionless: the sphere's optical radius.) The s axis is
// linear near 0 (ds/dk = ln(1 + s_max) / (n_s - 1) there), where the tables grow in
// proportion to s and a tube march multiplies hundreds of them: an axis in sqrt(s) would
// interpolate a linear start as sqrt(s) and dim empty space (measured: 25 % over a box).
// It is geometric beyond s ~ 1, where both tables vary slowly. Beyond s_max
// both tables hold their last column (the scattered light there is negligible; the table's
// module says how small); the direct term is analytic and exact at every s.
//
// Before including, declare `vec4 AMBIENT_TABLE_DIMS` as a macro or variable:
// (n_theta, n_s, n_g, s_max).
#ifndef REFRAKT_AMBIENT_TABLE_GLSL
#define REFRAKT_AMBIENT_TABLE_GLSL

const float AMBIENT_G_MAX = 0.99;

float ambient_node_coord(float index, float n) {
    return (clamp(index, 0.0, n - 1.0) + 0.5) / n;
}

float ambient_s_coord(float s) {
    vec4 d = AMBIENT_TABLE_DIMS;
    float u = log(1.0 + clamp(s, 0.0, d.w)) / log(1.0 + d.w);
    return ambient_node_coord(u * (d.y - 1.0), d.y);
}

float ambient_g_coord(float g) {
    vec4 d = AMBIENT_TABLE_DIMS;
    return ambient_node_coord((g + AMBIENT_G_MAX) / (2.0 * AMBIENT_G_MAX) * (d.z - 1.0), d.z);
}

float ambient_theta_coord(float cos_theta) {
    vec4 d = AMBIENT_TABLE_DIMS;
    float theta = acos(clamp(cos_theta, -1.0, 1.0));
    return ambient_node_coord(theta * (1.0 / 3.14159265358979) * (d.x - 1.0), d.x);
}

#include "phase.glsl"

#endif

#version 460
// See light_splat.vert: the part of one light ray's deposit that this pixel receives.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"

layout(location = 0) flat in vec4 flux_a;
layout(location = 1) flat in vec4 flux_b;
layout(location = 2) flat in vec4 footprint;
layout(location = 3) flat in vec4 corners_ab;
layout(location = 4) flat in vec4 corners_cd;
layout(location = 5) flat in vec3 direction;
layout(location = 6) flat in vec4 box_amplitude;
layout(location = 7) flat in vec4 box;
layout(location = 8) flat in vec4 flux_c;
layout(location = 9) flat in vec4 flux_d;

layout(location = 0) out vec4 out_irradiance;
layout(location = 1) out vec4 out_direction;

void main() {
    RayDeposit d;
    d.flux_a = flux_a;
    d.flux_b = flux_b;
    d.flux_c = flux_c;
    d.flux_d = flux_d;
    d.footprint = footprint;
    d.corners_ab = corners_ab;
    d.corners_cd = corners_cd;
    d.direction = direction;
    d.box_amplitude = box_amplitude;
    d.box = box;
    vec3 e;
    vec4 dir;
    deposit_at(d, floor(gl_FragCoord.xy), 1.0, e, dir);
    if (!(dir.w > 0.0) && !(max(e.r, max(e.g, e.b)) > 0.0)) discard;
    out_irradiance = vec4(e, 0.0);
    out_direction = dir;
}

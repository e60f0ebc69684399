#version 460
// Rays traced through the volume's refractive-index field by glsl/ray_equation.glsl to a
// target plane, or wavefront particles advanced for a time, one per invocation: the GPU integrator's check against the CPU photon
// tracer (tests/ray_equation.rs; render/ray_equation.rs) and its first user.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1) uniform sampler1DArray tf;
layout(std430, set = 0, binding = 2) readonly buffer Starts {
    vec4 starts[];  // pairs: origin (world, w unused), direction (w unused)
};
layout(std430, set = 0, binding = 3) writeonly buffer Ends {
    vec4 ends[];    // triples: position (w = arc length), direction (w = |v|),
                    // transmittance rgb (w = 1 on the plane, 0 lost or out of steps)
};
layout(push_constant) uniform Push {
    vec4 half_extent;  // xyz: the box's half extent; w: the reference step
    vec4 dims;         // xyz: voxels per axis; w: the eta scale k
    vec4 target;       // xyz: the target plane's unit normal n; w: c (n . x = c on it)
    float step;        // RK4 step: arc length (mode 0) or time (mode 1), world units
    uint max_steps;
    uint count;
    uint mode;         // 0: arc-length steps to the target plane; 1: max_steps
                       //    equi-temporal steps (eqs. 14-15), the plane unused
} pc;

// Whether eta is the cubic B-spline of the values (the eikonal model's `--cubic-eta`),
// ray_equation.glsl's RAY_CUBIC.
layout(constant_id = 0) const bool PROBE_CUBIC = false;
#define RAY_CUBIC PROBE_CUBIC
#define RAY_VOLUME volume
#define RAY_TF tf
#define RAY_HALF pc.half_extent.xyz
#define RAY_DIMS pc.dims.xyz
#define RAY_REF_STEP pc.half_extent.w
#define RAY_ETA_SCALE pc.dims.w
#include "ray_equation.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 x = starts[2 * i].xyz;
    vec3 v = normalize(starts[2 * i + 1].xyz) * ray_eta(x);
    vec3 n = pc.target.xyz;
    vec3 tau = vec3(0.0);
    float s = 0.0;
    // Outside the box and a step's margin the field is uniform: a ray there that does
    // not reach the plane never will (no backward rays are traced here).
    vec3 bound = pc.half_extent.xyz + vec3(2.0 * pc.step);
    float on_plane = 0.0;
    if (pc.mode == 1u) {
        // The wavefront's particle: a fixed time, attenuation along each step's chord.
        for (uint k = 0u; k < pc.max_steps; ++k) {
            vec3 x0 = x;
            ray_rk4_temporal(x, v, pc.step);
            float len = length(x - x0);
            tau += ray_optical_depth(x0, x, len);
            s += len;
        }
        ends[3 * i] = vec4(x, s);
        ends[3 * i + 1] = vec4(normalize(v), length(v));
        ends[3 * i + 2] = vec4(exp(-tau), 1.0);
        return;
    }
    for (uint k = 0u; k < pc.max_steps; ++k) {
        vec3 x0 = x, v0 = v;
        ray_rk4(x, v, pc.step);
        float d0 = dot(n, x0) - pc.target.w, d1 = dot(n, x) - pc.target.w;
        if (d1 >= 0.0) {
            // Crossed the plane within this step: the point on the chord, linearly
            // (as the CPU tracer does), and the direction and attenuation to it.
            float f = d0 < 0.0 ? -d0 / (d1 - d0) : 0.0;
            vec3 xe = mix(x0, x, f);
            tau += ray_optical_depth(x0, xe, f * pc.step);
            x = xe;
            v = mix(v0, v, f);
            s += f * pc.step;
            on_plane = 1.0;
            break;
        }
        tau += ray_optical_depth(x0, x, pc.step);
        s += pc.step;
        if (any(greaterThan(abs(x), bound)) && dot(n, v) <= 0.0) break;
    }
    ends[3 * i] = vec4(x, s);
    ends[3 * i + 1] = vec4(normalize(v), length(v));
    ends[3 * i + 2] = vec4(exp(-tau), on_plane);
}

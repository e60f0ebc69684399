#version 460
// The eikonal model's view renderer (issue 35 item 2; seed 001, Ihrke et al., sect. 4.1 and
// 5.3): one viewing ray per pixel, integrated through the refractive-index field with the
// ray equation (eqs. 11-12; ray_rk4, the photon tracer's integrator), lit by the light
// simulator's fluence volume (render/light_simulator.rs) instead of a light swept with it.
// Per step of arc length h, the segment's matter (the transfer function at the chord's
// midpoint: colour c, opacity a per reference step, medium colour m) scatters the light
// arriving there towards the eye through the Henyey-Greenstein phase function:
//
//   shade = albedo * (|d| 4pi p_HG(d^ . -dir; g) + (1 - |d|)) * fluence,
//
// d the voxel's luminance-weighted mean light direction (unit where one wavefront crosses
// it; shorter where several cross, whose spread the seed's one direction per voxel cannot
// hold, so that part is scattered as if isotropic), normalised as the single-scattering
// model is (4pi p = 1 for g = 0: an EA image where fluence and albedo are 1); composited
// front to back as the sweep composites (Oddy-Willis, eq. 4.13: the medium factor once),
//
//   C += (1 - A) M c a_h shade,  A += (1 - A) a_h,  M *= m^(h / ref),
//   a_h = 1 - (1 - a)^(h / ref),
//
// and what the ray sees where it leaves the box (the environment in its bent direction, or
// the background) through (1 - A) M.
//
// Dispersion (issue 35 item 3; render/eikonal/dispersion.rs): each colour channel's
// refractive index is the field's scaled about 1 by its own factor (eta_scales). A ray is
// traced first with red's; if it met no gradient of eta its path is every channel's and
// its colour is kept whole, else it is traced again with green's and blue's and each
// trace gives its own channel (the light volume holds each channel's own wavefront).
// Not yet here: the Fresnel split at faces (the ray
// refracts through every face; the reflected part is not traced) and an ambient term.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8) in;

// Bindings 0-4 as every ray-marched model's (render/march.rs, RayMarchPass); then the
// environment and the light volume.
layout(set = 0, binding = 0) uniform Params {
    vec4 cam_pos;      // xyz: the eye (world); w: tan(fov_y / 2)
    vec4 cam_forward;  // w: aspect (width / height)
    vec4 cam_right;
    vec4 cam_up;
    vec4 box_half;     // xyz: the box's half extent; w: the reference step
    vec4 background;   // linear rgba behind the volume (no environment)
    vec4 march;        // x: sample distance (reference steps); y: stop at this opacity
    uvec4 size;        // x, y: the image
    // As ea.comp up to here.
    vec4 field;        // xyz: the volume's voxels per axis; w: the eta scale k
    vec4 scatter;      // x: g; y: albedo; z: environment rotation (rad); w: 1 = environment map
    vec4 eta_scales;   // xyz: the eta scale k per colour channel (all P.field.w without dispersion)
    uvec4 steps;       // x: steps at most per ray; y: colour channels traced apart (1 or 3)
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;  // bound for the march layout; unread
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;
layout(set = 0, binding = 5) uniform sampler2D environment;
// Per voxel of the light volume (the volume's grid, x fastest): fluence rgb (w unused),
// then the mean light direction xyz (w unused).
layout(std430, set = 0, binding = 6) readonly buffer Light {
    vec4 light[];
};

#define RAY_VOLUME volume
#define RAY_TF tf
#define RAY_HALF P.box_half.xyz
#define RAY_DIMS P.field.xyz
#define RAY_REF_STEP P.box_half.w
// The eta scale of the channel being traced (trace_ray sets it).
float ray_k = 1.0;
#define RAY_ETA_SCALE ray_k
#include "ray_equation.glsl"
#include "raycast.glsl"
#include "environment.glsl"
#include "phase.glsl"
#define LIGHT_VOLUME light
#include "light_volume.glsl"

// The fluence and mean direction at world point w (glsl/light_volume.glsl).
void light_at(vec3 w, out vec3 fluence, out vec3 direction) {
    light_volume_at(ray_tex(w), P.field.xyz, fluence, direction);
}

vec3 background_seen(vec3 dir) {
    if (P.scatter.w < 0.5) return P.background.rgb;
    float r = P.scatter.z;
    vec3 w = vec3(cos(r) * dir.x - sin(r) * dir.z, dir.y, sin(r) * dir.x + cos(r) * dir.z);
    return env_bilinear(environment, env_texel(env_angles(w), textureSize(environment, 0)));
}

// The part of the chord from a to b (unit direction u, length len) inside the box.
float inside_length(vec3 a, vec3 u, float len) {
    float t0, t1;
    box_span(a, u, P.box_half.xyz, t0, t1);
    return max(min(t1, len) - t0, 0.0);
}

// The ray from the eye along `dir` with eta scale k: its colour and opacity, composited
// front to back, with what it sees behind; `bent` whether any gradient of eta turned it.
vec4 trace_ray(vec3 dir, float k, out bool bent) {
    ray_k = k;
    bent = false;
    vec3 eye = P.cam_pos.xyz;
    vec3 C = vec3(0.0), M = vec3(1.0);
    float A = 0.0;
    float t_near, t_far;
    box_span(eye, dir, P.box_half.xyz, t_near, t_far);
    if (t_far > t_near) {
        float ref = P.box_half.w, h = P.march.x * ref;
        // The sample distance is the longest step; faces and films take shorter ones
        // (ray_rk4_adaptive), down to a hundredth of a voxel.
        float h_try = h, h_min = min(0.01 * ref, h);
        vec3 x = eye + t_near * dir;
        vec3 v = dir * ray_eta(x);
        vec3 v_start = v;
        for (uint k = 0u; k < P.steps.x && A < P.march.y; ++k) {
            vec3 x0 = x;
            ray_rk4_adaptive(x, v, h_try, h, h_min);
            vec3 chord = x - x0;
            float len = length(chord);
            if (len <= 0.0) break;
            // Only the matter inside the box counts (outside it the value is 0, which a
            // transfer function may make opaque).
            float inside = inside_length(x0, chord / len, len);
            if (inside > 0.0) {
                vec3 mid = x0 + chord * (0.5 * inside / len);
                float s = ray_value(mid);
                vec4 ca = ray_tf(s, 0);
                vec3 m = ray_tf(s, 1).rgb;
                float ratio = inside / ref;
                float a = correct_opacity(ca.a, ratio);
                vec3 fluence, d;
                light_at(mid, fluence, d);
                float r = min(length(d), 1.0);
                vec3 u = normalize(v);
                float phase = r > 0.0 ? r * hg4pi(dot(d / length(d), -u), P.scatter.x) : 0.0;
                phase += 1.0 - r;
                vec3 shade = P.scatter.y * phase * fluence;
                C += (1.0 - A) * M * ca.rgb * a * shade;
                A += (1.0 - A) * a;
                M *= correct_medium(m, ratio);
            }
            // Left the box, moving away from it: the rest is uniform (eta 1 outside).
            bvec3 beyond = greaterThan(abs(x), P.box_half.xyz);
            bvec3 away = greaterThan(x * v, vec3(0.0));
            if (any(bvec3(beyond.x && away.x, beyond.y && away.y, beyond.z && away.z))) break;
        }
        // Unchanged only where every RK4 stage met a zero gradient.
        bent = any(notEqual(v, v_start));
        dir = normalize(v);
    }
    vec3 rgb = C + (1.0 - A) * M * background_seen(dir);
    float alpha = A + (1.0 - A) * (P.scatter.w < 0.5 ? P.background.a : 1.0);
    return vec4(rgb, alpha);
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz, P.cam_up.xyz);
    bool bent;
    vec4 seen = trace_ray(dir, P.eta_scales.x, bent);
    if (P.steps.y == 3u && bent) {
        // Dispersion: green and blue along their own paths; the opacity is the mean of
        // the three (each channel's path met its own matter).
        bool unused;
        vec4 green = trace_ray(dir, P.eta_scales.y, unused);
        vec4 blue = trace_ray(dir, P.eta_scales.z, unused);
        seen = vec4(seen.r, green.g, blue.b, (seen.a + green.a + blue.a) / 3.0);
    }
    imageStore(frame, ivec2(id), seen);
}

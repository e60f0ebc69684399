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
//
// Faces reflect (Fresnel; issue 35 item 2, with issue 32 item 4's reflections that see
// the volume), as the reference renderer splits its rays (src/photons/reference.rs,
// View::face): a face is where a step passes eta's middle between the plateaus probed
// FACE_PROBE voxels either side along grad eta, the plateaus differ by MIN_FACE_STEP or
// more (the sweep's threshold) and half-way out eta is already on either side. There the fraction F (unpolarised Fresnel between the
// plateaus, at the angle of v's tangential part, which a face keeps) leaves in the
// mirrored direction and the ray goes on with the rest (F folded into its opacity, as the
// sweep does). The first face's reflected ray is traced through the volume after the
// ray itself (one bounce: GLSL has no recursion), so glass shows the floor it stands on;
// later faces, and the faces the reflected ray meets, reflect the environment (or the
// background). Beyond the critical angle nothing splits: the ray equation turns the ray
// itself back. Films (eta rising and falling back within the probes) are not faces.
// P.steps.z: 1 with reflections (`--reflections`, the sweep's flag), 0 without.
//
// Emission is optional (`--emission E`, the image formation model's emission term): each
// sample also emits E times its colour per unit opacity (C += (1 - A) M c a_h E), as the
// emission-absorption model's samples do.
//
// The ambient level (`--ambient-level`, `--light env`; the sweep's SweepOptions::ambient,
// the map's mean radiance): every sample is lit by it besides the light volume,
// unoccluded and from no direction. A phase function normalised over the sphere turns a
// uniform radiance L into L, so it adds albedo * L to the shade above (a white medium of
// albedo 1 in a uniform map of radiance L shows L everywhere: the furnace test).
//
// What a ray sees where it leaves the box is averaged over the pixel's footprint (the
// sweep's composite, glsl/sweep_composite.comp, thesis Fig. 4.5): the directions in which
// the neighbouring pixels' rays leave span it, and the summed-area table averages the map
// over it. The neighbours are the workgroup's (the next invocation along x and along y,
// the previous one at the tile's edge), exchanged through shared memory once every ray of
// the tile is traced. A ray that no gradient bent reads the map at its point, as before;
// so do the reflections of faces after the first. The first face's reflected ray is
// filtered the same way, from the neighbours' reflected rays.
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
    uvec4 steps;       // x: steps at most per ray; y: colour channels traced apart (1 or 3);
                       // z: 1 = Fresnel reflections at faces; w: 1 = lookups filtered
                       // over the pixel's footprint (SweepOptions::env_footprint)
    vec4 ambient;      // rgb: the ambient level (mean radiance, unoccluded); w: the emission
    vec4 env_mean;     // rgb: the summed-area table's mean offset (environment.glsl)
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
// The environment's summed-area table (render/sat.rs; texelFetch only).
layout(set = 0, binding = 7) uniform sampler2D environment_sat;

// Whether eta is the cubic B-spline of the values (`--cubic-eta 1`: smooth glass; the
// trilinear field's iso-surfaces are corrugated at the voxels' period and scatter the
// environment seen through glass into speckle), ray_equation.glsl's RAY_CUBIC.
layout(constant_id = 0) const bool VIEW_CUBIC = false;
#define RAY_CUBIC VIEW_CUBIC
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
#include "fresnel.glsl"
#define LIGHT_VOLUME light
#include "light_volume.glsl"

// The fluence and mean direction at world point w (glsl/light_volume.glsl).
void light_at(vec3 w, out vec3 fluence, out vec3 direction) {
    light_volume_at(ray_tex(w), P.field.xyz, fluence, direction);
}

// A world direction in the map's frame (rotated by P.scatter.z about the up axis).
vec3 env_frame(vec3 dir) {
    float r = P.scatter.z;
    return vec3(cos(r) * dir.x - sin(r) * dir.z, dir.y, sin(r) * dir.x + cos(r) * dir.z);
}

vec3 background_seen(vec3 dir) {
    if (P.scatter.w < 0.5) return P.background.rgb;
    return env_bilinear(environment, env_texel(env_angles(env_frame(dir)), textureSize(environment, 0)));
}

// What the rays leaving in directions d +- dx / 2 +- dy / 2 see: the map averaged over
// that footprint (environment.glsl's env_footprint; a footprint of a texel or less is
// read bilinearly there).
vec3 background_over(vec3 d, vec3 dx, vec3 dy) {
    if (P.scatter.w < 0.5) return P.background.rgb;
    vec3 ds[4] = vec3[4](env_frame(d - 0.5 * dx - 0.5 * dy), env_frame(d + 0.5 * dx - 0.5 * dy),
                         env_frame(d - 0.5 * dx + 0.5 * dy), env_frame(d + 0.5 * dx + 0.5 * dy));
    return env_footprint(environment, environment_sat, P.env_mean.rgb, ds);
}

// The part of the chord from a to b (unit direction u, length len) inside the box.
float inside_length(vec3 a, vec3 u, float len) {
    float t0, t1;
    box_span(a, u, P.box_half.xyz, t0, t1);
    return max(min(t1, len) - t0, 0.0);
}

// Smallest step of eta between a face's plateaus that reflects (the sweep's
// MIN_FACE_STEP, glsl/sweep_plane.glsl; the reference renderer's): below it the change
// is noise or a graded medium.
const float MIN_FACE_STEP = 0.02;
// How far either side of a step the face's plateaus are probed, in reference steps
// (beyond half the step): past a graded face's ramp of two or three voxels.
const float FACE_PROBE = 2.5;

// The face the step a -> b (eta eta_a, eta_b at its ends; v = va at a) crosses, if any:
// the fraction it reflects (0: none) and the mirrored direction (unit).
float face_split(vec3 a, vec3 b, float eta_a, float eta_b, vec3 va, out vec3 mirrored) {
    mirrored = vec3(0.0);
    if (abs(eta_b - eta_a) < 1e-7) return 0.0;
    vec3 mid = 0.5 * (a + b);
    vec3 g = ray_grad_eta(mid);
    if (dot(g, g) < 1e-20) return 0.0;
    vec3 n = normalize(g);
    float reach = 0.5 * length(b - a) + FACE_PROBE * P.box_half.w;
    float e_minus = ray_eta(mid - reach * n), e_plus = ray_eta(mid + reach * n);
    float lo = min(e_minus, e_plus), hi = max(e_minus, e_plus), middle = 0.5 * (lo + hi);
    if (hi - lo < MIN_FACE_STEP || (eta_a < middle) == (eta_b < middle)) return 0.0;
    // A step, not a film: half-way out eta lies on either side of the middle already. (A
    // film between two regions of equal eta, as an opaque block's skin passing through
    // a glass's values, read as a face where one probe reached the glass beyond it: the
    // block seen in the slab's reflection let 4-9 % of the environment through.)
    float h_minus = ray_eta(mid - 0.5 * reach * n), h_plus = ray_eta(mid + 0.5 * reach * n);
    if ((h_minus < middle) == (h_plus < middle)) return 0.0;
    if (e_plus < e_minus) n = -n;   // towards higher eta
    // The angle on the low side from the tangential part of v (kept across a face).
    vec3 vt = va - dot(va, n) * n;
    float vt_len = length(vt);
    if (vt_len >= lo) return 0.0;   // totally reflected: the ray equation turns the ray
    // The incident direction on the side the ray comes from, mirrored about the face.
    float eta_in = eta_b > eta_a ? lo : hi;
    float vn = sqrt(max(eta_in * eta_in - vt_len * vt_len, 0.0));
    vec3 incident = (vt + (dot(va, n) >= 0.0 ? vn : -vn) * n) / eta_in;
    mirrored = normalize(incident - 2.0 * dot(incident, n) * n);
    return face_fresnel(vt_len, lo, hi);
}

// A traced ray: its colour C and opacity A composited front to back, its medium M, the
// direction it leaves in (unit) and whether any gradient of eta turned it.
struct Trace {
    vec3 C;
    float A;
    vec3 M;
    vec3 exit_dir;
    bool bent;
};

// The ray from `origin` along `dir` with eta scale k (what lies behind it is the caller's:
// (1 - A) M times the background in exit_dir). With `split`, the first face it meets
// hands its reflected ray back (from `r_origin` along `r_dir`, to be traced with its
// colour weighted by `r_weight`, (1 - A) M F there; r_weight stays 0 where it met none);
// the other faces' reflections see what lies behind them at once.
Trace trace_ray(vec3 origin, vec3 dir, float k, bool split, out vec3 r_origin, out vec3 r_dir,
                out vec3 r_weight) {
    ray_k = k;
    Trace t;
    t.bent = false;
    r_origin = vec3(0.0);
    r_dir = vec3(0.0, 0.0, 1.0);
    r_weight = vec3(0.0);
    bool reflections = P.steps.z != 0u;
    vec3 C = vec3(0.0), M = vec3(1.0);
    float A = 0.0;
    float t_near, t_far;
    box_span(origin, dir, P.box_half.xyz, t_near, t_far);
    t_near = max(t_near, 0.0);   // a reflected ray starts inside the box
    if (t_far > t_near) {
        float ref = P.box_half.w, h = P.march.x * ref;
        // The sample distance is the longest step; faces and films take shorter ones
        // (ray_rk4_adaptive), down to a hundredth of a voxel.
        float h_try = h, h_min = min(0.01 * ref, h);
        vec3 x = origin + t_near * dir;
        float eta_x = ray_eta(x);
        vec3 v = dir * eta_x;
        vec3 v_start = v;
        for (uint k = 0u; k < P.steps.x && A < P.march.y; ++k) {
            vec3 x0 = x, v0 = v;
            float eta_0 = eta_x;
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
                // The light volume's light through the phase function, and the ambient
                // level (uniform radiance: the phase function integrates it to itself).
                // With the optional emission (P.ambient.w; seed 001 sect. 4.1) the sample
                // also emits its colour, as the emission-absorption model's do.
                vec3 shade = P.scatter.y * (phase * fluence + P.ambient.rgb) + P.ambient.w;
                C += (1.0 - A) * M * ca.rgb * a * shade;
                A += (1.0 - A) * a;
                M *= correct_medium(m, ratio);
            }
            if (reflections) {
                eta_x = ray_eta(x);
                vec3 mirrored;
                float F = face_split(x0, x, eta_0, eta_x, v0, mirrored);
                if (F > 0.0) {
                    vec3 w = (1.0 - A) * M * F;
                    if (split && r_weight == vec3(0.0)) {
                        r_origin = x0;
                        r_dir = mirrored;
                        r_weight = w;
                    } else {
                        C += w * background_seen(mirrored);
                    }
                    A += (1.0 - A) * F;
                }
            }
            // Left the box, moving away from it: the rest is uniform (eta 1 outside).
            bvec3 beyond = greaterThan(abs(x), P.box_half.xyz);
            bvec3 away = greaterThan(x * v, vec3(0.0));
            if (any(bvec3(beyond.x && away.x, beyond.y && away.y, beyond.z && away.z))) break;
        }
        // Unchanged only where every RK4 stage met a zero gradient.
        t.bent = any(notEqual(v, v_start));
        dir = normalize(v);
    }
    t.C = C;
    t.A = A;
    t.M = M;
    t.exit_dir = dir;
    return t;
}

// A pixel's view along one channel's path: the colour so far (the ray's and its first
// reflection's, everything but what they see leaving the box), the opacity with what
// lies behind, and per lookup still to make (0: the ray, 1: its first face's reflected
// ray) its weight, direction, and whether it is filtered over the footprint (the ray:
// where bent; the reflected ray: always) or read at its point. A weight of 0 marks no
// lookup (no reflection).
struct View {
    vec3 rgb;
    float alpha;
    vec3 weight[2];
    vec3 dir[2];
    bool filtered[2];
};

// The viewing ray from the eye along `dir` with eta scale k, and the reflected ray of the
// first face it meets, traced through the volume.
View view_ray(vec3 dir, float k) {
    vec3 r_origin, r_dir, r_weight;
    Trace t = trace_ray(P.cam_pos.xyz, dir, k, true, r_origin, r_dir, r_weight);
    View v;
    v.rgb = t.C;
    v.alpha = t.A + (1.0 - t.A) * (P.scatter.w < 0.5 ? P.background.a : 1.0);
    v.weight[0] = (1.0 - t.A) * t.M;
    v.dir[0] = t.exit_dir;
    v.filtered[0] = t.bent;
    v.weight[1] = vec3(0.0);
    v.dir[1] = vec3(0.0, 0.0, 1.0);
    v.filtered[1] = true;
    if (r_weight != vec3(0.0)) {
        vec3 o2, d2, w2;
        Trace r = trace_ray(r_origin, r_dir, k, false, o2, d2, w2);
        v.rgb += r_weight * r.C;
        v.weight[1] = r_weight * (1.0 - r.A) * r.M;
        v.dir[1] = r.exit_dir;
    }
    return v;
}

// Per invocation of the tile, one lookup's direction (xyz; w 1 where it has one), for the
// neighbours' footprints.
shared vec4 lookup_dirs[64];

// The change of the lookup direction d towards the tile's next invocation along `axis` (0:
// x, 1: y), or from its previous one at the tile's edge or where the next has none; 0 where
// neither has one.
vec3 neighbour_delta(uvec2 l, int axis, vec3 d) {
    uvec2 next = l, prev = l;
    next[axis] += 1u;
    prev[axis] -= 1u;
    if (l[axis] < 7u) {
        vec4 n = lookup_dirs[next.y * 8u + next.x];
        if (n.w > 0.5) return n.xyz - d;
    }
    if (l[axis] > 0u) {
        vec4 p = lookup_dirs[prev.y * 8u + prev.x];
        if (p.w > 0.5) return d - p.xyz;
    }
    return vec3(0.0);
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    uvec2 l = gl_LocalInvocationID.xy;
    uint lane = gl_LocalInvocationIndex;
    // Invocations beyond the image trace nothing but take part in the tile's exchanges.
    bool live = all(lessThan(id, P.size.xy));
    View views[3];
    uint channels = live && P.steps.y == 3u ? 3u : 1u;
    if (live) {
        vec3 dir = camera_ray(id, P.size.xy, P.cam_pos, P.cam_forward, P.cam_right.xyz,
                              P.cam_up.xyz);
        views[0] = view_ray(dir, P.eta_scales.x);
        views[1] = views[0];
        views[2] = views[0];
        if (P.steps.y == 3u && views[0].filtered[0]) {
            // Dispersion: green and blue along their own paths (where red's was bent);
            // the opacity is the mean of the three (each channel's path met its own
            // matter).
            views[1] = view_ray(dir, P.eta_scales.y);
            views[2] = view_ray(dir, P.eta_scales.z);
        } else {
            channels = 1u;
        }
    }
    vec3 rgb = vec3(0.0);
    float alpha = 0.0;
    for (uint c = 0u; c < 3u; ++c) {
        if (live) {
            rgb[c] = views[c].rgb[c];
            alpha += views[c].alpha / 3.0;
        }
    }
    // The lookups, per channel path and per ray (the ray, its reflected ray), each after
    // the tile has shared its directions. Loops of fixed length: every invocation meets
    // every barrier.
    bool footprint = P.steps.w != 0u && P.scatter.w > 0.5;
    for (uint c = 0u; c < 3u; ++c) {
        // Without dispersion the three channels share red's path: one round (a uniform
        // condition: the whole tile leaves together).
        if (c > 0u && P.steps.y != 3u) break;
        for (uint j = 0u; j < 2u; ++j) {
            // A pixel whose path was not split into channels offers red's to its
            // neighbours (views[c] is views[0] there) and adds it once, in round 0.
            bool has = live && views[c].weight[j] != vec3(0.0);
            vec3 d = has ? views[c].dir[j] : vec3(0.0);
            lookup_dirs[lane] = vec4(d, has ? 1.0 : 0.0);
            barrier();
            if (has && c < channels) {
                vec3 seen;
                if (footprint && views[c].filtered[j]) {
                    seen = background_over(d, neighbour_delta(l, 0, d), neighbour_delta(l, 1, d));
                } else {
                    seen = background_seen(d);
                }
                vec3 add = views[c].weight[j] * seen;
                if (channels == 1u) {
                    rgb += add;
                } else {
                    rgb[c] += add[c];
                }
            }
            barrier();
        }
    }
    if (live) imageStore(frame, ivec2(id), vec4(rgb, channels == 3u ? alpha : views[0].alpha));
}

// Reflections that see the volume (issue 32 item 4; `--reflections volume`), for the
// sweep's composite (glsl/sweep_composite.comp). The sweep reflects the environment at
// every face a viewing ray meets (sweep_viewing.glsl, composite_segment): the mirrored
// ray leaves the plane the sweep is on and may go anywhere, also towards planes not yet
// swept, so it cannot be traced during the sweep. After the sweep, everything it needs is
// known: the first face of a viewing ray lies on the straight camera ray (nothing bent
// it before), and the light of the planes is kept, every `stride`-th plane, in the light
// record (render::refract::LightRecord). So the composite finds each pixel's first face
// again, traces the mirrored ray straight through the volume (emission-absorption with
// the preintegrated segments, lit by the recorded light with the sweep's layer law, the
// ambient level beside it) to the environment, and replaces the environment the sweep
// reflected there by what that ray sees:
//
//     C += w F (L_volume - L_env),   w = (1 - A) M at the face (eq. 4.13)
//
// Where the mirrored ray meets nothing, L_volume = L_env and the image is the sweep's
// exactly. Limits (docs/NOTES.md): one bounce (the faces the mirrored ray meets pass it
// on unturned, GLSL has no recursion); the light is the planes', which cover the view's
// frustum only (a point outside it reads the nearest edge of the plane); a smooth η
// gradient before the first face bends the sweep's ray but not this search.
#ifndef REFRAKT_SWEEP_REFLECT_GLSL
#define REFRAKT_SWEEP_REFLECT_GLSL

#include "fresnel.glsl"

layout(set = 0, binding = 14) uniform sampler2DArray light_record;
// The smoothed gradient (render::gradient; xyz in value units per voxel), when bound.
layout(set = 0, binding = 15) uniform sampler3D gradient_volume;

// The face's normal direction at view-space p: the smoothed gradient the sweep's faces
// use where it is bound (the exact gradient of the trilinear field is corrugated on a
// voxelised curved surface, 1-3° off: mirrored at grazing angles towards a floor's
// shadow edge and caustic, that was speckle); otherwise the trilinear field's own.
vec3 face_gradient(vec3 p) {
    vec3 t = to_tex(p);
    bool inside = all(greaterThanEqual(t, vec3(0.0))) && all(lessThanEqual(t, vec3(1.0)));
    vec3 smoothed = transpose(mat3(P.view_to_tex))
                  * (textureLod(gradient_volume, t, 0.0).xyz * P.volume_dims.xyz);
    return pc.have_gradient != 0u && inside ? smoothed : value_gradient(p);
}

// The step of eta a face has at least (the sweep's, glsl/sweep_plane.glsl).
const float REFLECT_MIN_FACE_STEP = 0.02;
// How far beyond the first change of eta its plateau is looked for (reference steps):
// a graded face's whole step (sweep_plane.glsl probes 2.5 voxels either side).
const float REFLECT_PLATEAU_STEPS = 3.0;

// Loop bounds are constants or per-pixel values, never a uniform alone: lavapipe inlines
// uniform values that decide a branch or a loop's end and compiles a shader variant per
// value (docs/NOTES.md, "A lavapipe trap: inlined uniforms"). With the plane count as a
// bound, every frame of a moving camera compiled this shader again: 350 ms a frame on
// an empty Mesa cache. Steps along a ray at most (a box's diagonal at sample distance
// 1/8 of a 1024³ volume), and steps to a graded face's middle at most.
const int REFLECT_MAX_STEPS = 16384;
const int REFLECT_MAX_RAMP_STEPS = 64;

// The eikonal transport's light volume (`--light-transport eikonal`): the light at any
// point from the simulator, when the planes carry none.
layout(std430, set = 0, binding = 16) readonly buffer LightVolume {
    vec4 light_volume[];
};
#define LIGHT_VOLUME light_volume
#include "light_volume.glsl"

// The light at view-space point p: with the eikonal transport the light volume's;
// otherwise the recorded planes' either side of p's depth, bilinear within each (the
// record's sampler), linear between them. (Both read, one chosen: see trace_reflected.)
vec3 recorded_light(vec3 p, uint stride) {
    // Without the eikonal transport binding 16 holds a placeholder of two texels: the
    // lookup is then made on a grid of one voxel, which reads only those.
    bool from_volume = pc.light_from_volume != 0u;
    vec3 fluence, direction;
    light_volume_at(to_tex(p), from_volume ? P.volume_dims.xyz : vec3(1.0), fluence, direction);
    float last = P.planes.z - 1.0;
    float f = clamp((p.z - P.planes.x) / P.planes.y, 0.0, last);
    float top = min(floor(last / float(stride)), float(textureSize(light_record, 0).z - 1));
    float layer = min(f / float(stride), top);
    float l0 = floor(layer);
    float l1 = min(l0 + 1.0, top);
    vec2 uv = project(p);
    vec3 a = textureLod(light_record, vec3(uv, l0), 0.0).rgb;
    vec3 b = textureLod(light_record, vec3(uv, l1), 0.0).rgb;
    return from_volume ? fluence : mix(a, b, layer - l0);
}

// Where view-space ray o + t d is inside the volume's box: [t0, t1] (t0 > t1: never).
vec2 box_span(vec3 o, vec3 d) {
    vec3 ot = to_tex(o);
    vec3 dt = mat3(P.view_to_tex) * d;
    vec3 inv = 1.0 / dt;
    vec3 a = (vec3(0.0) - ot) * inv;
    vec3 b = (vec3(1.0) - ot) * inv;
    vec3 lo = min(a, b), hi = max(a, b);
    return vec2(max(max(lo.x, lo.y), max(lo.z, 0.0)), min(min(hi.x, hi.y), hi.z));
}

// What ray p + t r (r unit, view space) sees from t = 0 through the volume, then the
// environment env_seen: emission-absorption with the preintegrated segments (one plane
// spacing each), each lit by the recorded light with the sweep's layer law
// (sweep_viewing.glsl, segment_light: a layer's light meets it at |n.l| where the ray
// crosses it at |n.r|) and the ambient level; up to opacity P.termination_alpha.
vec3 trace_reflected(vec3 p, vec3 r, vec3 env_seen, uint stride) {
    vec2 span = box_span(p, r);
    float h = P.planes.y;
    int steps = span.y > span.x ? min(int(ceil((span.y - span.x) / h)), REFLECT_MAX_STEPS) : 0;
    vec3 C = vec3(0.0), M = vec3(1.0);
    float A = 0.0;
    vec3 l = P.light_dir.xyz;
    float v_prev = value_at_tex(to_tex(p + r * span.x));
    for (int k = 1; k <= steps; ++k) {
        if (A >= P.termination_alpha) break;
        vec3 q = p + r * (span.x + float(k) * h);
        float v = value_at_tex(to_tex(q));
        vec3 c; float a; vec3 m;
        segment(v_prev, v, h / P.planes.w, false, c, a, m);
        // The recorded light is the light at each point, having crossed whatever lies
        // between it and the light: in homogeneous matter it is read in the segment's
        // middle (second order in the step). Across layers of matter (a surface's skin,
        // thinner than the record's planes and pixels resolve) it is read where the
        // segment begins, outside the skin, and the skin shades itself by the sweep's
        // layer law (segment_light): the light crosses |n.r| / |n.l| of the skin for
        // each unit the ray does.
        vec3 g = value_gradient(q);
        bool layered = abs(v - v_prev) > 1e-4 && dot(g, g) > 1e-12;
        vec3 n = layered ? normalize(g) : vec3(0.0, 0.0, 1.0);
        float rr = layered ? abs(dot(n, r)) / max(abs(dot(n, l)), MIN_FORWARD) : 0.0;
        float kk = 1.0 + rr;
        float shade = a > 1e-4 ? (1.0 - pow(1.0 - a, kk)) / (kk * a) : 1.0 - 0.5 * rr * a;
        vec3 light = recorded_light(q - r * (layered ? h : 0.5 * h), stride);
        // Unlit (the diagnostic): i_d = 1, no layer law, no ambient level, as the sweep.
        // (Chosen, not branched: lavapipe compiles a variant per value of a uniform that
        // decides a branch, and this shader's uniforms change with the camera.)
        bool lit = P.unlit == 0u;
        vec3 i_d = lit ? light : vec3(1.0);
        vec3 c_ambient = lit ? c : vec3(0.0);
        c *= lit ? shade : 1.0;
        C += (1.0 - A) * M * (c * i_d + c_ambient * P.ambient.rgb);
        A += (1.0 - A) * a;
        M *= m;
        v_prev = v;
    }
    return C + (1.0 - A) * M * env_seen;
}

// The first face on the camera ray of uv (straight until it), as the sweep meets it: the
// first place where eta has changed by REFLECT_MIN_FACE_STEP from the eta the ray started
// in and stays changed a few voxels on (not a film). Returns F > 0 there, with the point
// the mirrored ray starts from, the mirrored direction and the weight
// (1 - A) M of what lies before it (eq. 4.13); 0 where there is no face, the ray was
// opaque before it, the face reflects totally (the sweep turns the ray itself back
// there), or `search` is false (no search: the loops run no trips).
float first_face(vec2 uv, bool search, out vec3 face, out vec3 mirrored, out vec3 weight) {
    vec3 d = normalize(plane_point(uv, 1.0));
    vec2 span = box_span(vec3(0.0), d);
    float h = P.planes.y;
    int steps = search && span.y > span.x
                    ? min(int(ceil((span.y - span.x) / h)), REFLECT_MAX_STEPS) : 0;
    face = vec3(0.0);
    mirrored = d;
    weight = vec3(0.0);
    vec3 M = vec3(1.0);
    float A = 0.0;
    float t_prev = span.x;
    float v_prev = value_at_tex(to_tex(d * t_prev));
    float eta0 = eta_of(v_prev);
    float t_face = -1.0;
    // A face's plateau: eta a few reference steps on, past a graded face's ramp.
    float beyond = REFLECT_PLATEAU_STEPS * P.planes.w;
    float eta1 = eta0;
    for (int k = 1; k <= steps; ++k) {
        float t = span.x + float(k) * h;
        float v = value_at_tex(to_tex(d * t));
        if (abs(eta_of(v) - eta0) >= REFLECT_MIN_FACE_STEP) {
            // A face, unless eta comes back beyond it: a film (a matter's value ramp
            // passing another's eta band within a voxel), which belongs to no matter
            // and which the sweep does not reflect at (sweep_viewing.glsl, face_met).
            eta1 = eta_of(value_at_tex(to_tex(d * (t + beyond))));
            if (abs(eta1 - eta0) >= REFLECT_MIN_FACE_STEP) {
                t_face = t;
                break;
            }
        }
        vec3 c; float a; vec3 m;
        segment(v_prev, v, h / P.planes.w, false, c, a, m);
        A += (1.0 - A) * a;
        M *= m;
        if (A >= P.termination_alpha) break;
        t_prev = t;
        v_prev = v;
    }
    // (Without a face the loops below run no trips: llvmpipe runs what follows a return
    // in a branch anyway, masked.)
    if (t_face < 0.0) return 0.0;
    bool found = t_face >= 0.0;
    // The face where eta passes the middle of the step: bisection within the last step.
    float mid = 0.5 * (eta0 + eta1);
    float lo = t_prev, hi = t_face;
    // A graded face (eta ramping over a few voxels) passes its middle further on.
    int more = found ? REFLECT_MAX_RAMP_STEPS : 0;
    for (int k = 0; k < more; ++k) {
        if (hi > t_face + beyond) break;
        if ((eta_of(value_at_tex(to_tex(d * hi))) - mid) * (eta1 - eta0) >= 0.0) break;
        lo = hi;
        hi += h;
    }
    for (int k = 0; k < (found ? 12 : 0); ++k) {
        float t = 0.5 * (lo + hi);
        bool before = (eta_of(value_at_tex(to_tex(d * t))) - mid) * (eta1 - eta0) < 0.0;
        if (before) lo = t; else hi = t;
    }
    float t_mid = 0.5 * (lo + hi);
    vec3 g = face_gradient(d * t_mid);
    if (!(dot(g, g) > 1e-12)) return 0.0;
    vec3 n = normalize(g);
    if (dot(n, d) > 0.0) n = -n;
    float cos_i = -dot(n, d);
    float f = face_fresnel(eta0 * sqrt(max(1.0 - cos_i * cos_i, 0.0)), eta0, eta1);
    if (f >= 1.0) return 0.0;
    mirrored = reflect(d, n);
    // The mirrored ray starts on the side the viewing ray came from, as far from the
    // face as the last sample before it: from the middle of the face's ramp it would
    // cross the reflecting matter's own skin (an opaque floor's, under its face).
    face = d * t_mid + n * (cos_i * (t_mid - t_prev));
    weight = (1.0 - A) * M;
    return f;
}

#endif

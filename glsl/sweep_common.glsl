// Shared by the plane-sweep passes (sweep_setup.comp, sweep.frag, sweep_composite.comp).
// View space: x right, y up, z forward (depth along the view direction), world units
// (the volume's longest side is 1). Equation numbers refer to the thesis.
#ifndef REFRAKT_SWEEP_COMMON_GLSL
#define REFRAKT_SWEEP_COMMON_GLSL
#include "common.glsl"

// std140 mirror of render::refract::SweepParams.
layout(set = 0, binding = 0) uniform SweepParams {
    mat4 view_to_tex;    // view space -> volume texture coordinates in [0,1]^3
    mat4 view_to_world;  // for the clipping plane
    vec4 camera;         // x = tan(fov_y / 2), y = aspect, z = width, w = height
    vec4 planes;         // x = depth of plane 0, y = spacing ds, z = plane count, w = reference step
    vec4 light_dir;      // xyz = direction light travels (view space, unit), w = softness
                         //   (filter radius per plane, in reference steps)
    vec4 light_colour;   // rgb, w unused
    vec4 volume_dims;    // xyz = voxels per axis, w unused
    vec4 specular;       // x = roughness, y = specular strength, zw unused
    vec4 clip;           // xyz = world normal, w = offset: opacity is zero where dot(n, p) > w;
                         // a zero normal disables clipping
    vec4 background;     // linear RGBA behind the volume
    vec4 refraction;     // x = refractive-index scale k: eta' = 1 + k (eta_tf - 1); y = 1 for
                         //   Fresnel reflections of viewing rays; z = 1 when an environment
                         //   map is bound; w = its rotation about world up (radians)
    vec4 light_grid;     // forward transport: the light rays' grid on the launch plane
                         //   (view x, y of ray (0,0)'s cell corner; cell size x, y)
    vec4 transport;      // x = 1 forward light transport, 0 backward; y = diffusion weight
                         //   per neighbour (softness); z = diffusion stride in rays;
                         //   w = largest splat half-width in pixels
    vec4 light_rays;     // forward transport: x, y = the rays' grid (columns, rows); z, w =
                         //   the ray images' size (ray r lives at texel (r % z, r / z))
    float max_gain;      // bound on the backward step's intensity gain per plane
    float termination_alpha;  // a viewing ray stops compositing at this opacity
    uint unlit;          // 1: diagnostic, i_d = 1 and no highlights
    uint pad0;
    vec4 ambient;        // rgb: the ambient level every sample is lit by, unoccluded, besides
                         //   the light (--light env: the map's mean radiance); 0 = the thesis
} P;

// medium.w of a viewing ray the setup left on plane 0 (its depth is then the first
// plane's, not the plane's it is read on): catch_up_to_plane moves it on and clears the
// mark. Above -1, so never a finished ray's mark (-(k + 1)), below 0, so never a chain.
const float VIEW_RAY_AT_SETUP = -0.5;

layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;       // layer 1 .a = eta
layout(set = 0, binding = 3) uniform sampler2DArray preint;   // preintegration table

// Preintegrated segment from value a to value b, `ratio` reference steps long:
// premultiplied colour, opacity (eq. 3.19), medium (power rule).
void segment(float a, float b, float ratio, bool clip, out vec3 colour, out float alpha,
             out vec3 m) {
    vec2 c = preint_coord(a, b);
    vec4 ca = textureLod(preint, vec3(c, 0.0), 0.0);
    m = correct_medium(textureLod(preint, vec3(c, 1.0), 0.0).rgb, ratio);
    alpha = correct_opacity(ca.a, ratio);
    colour = ca.a > 1e-6 ? ca.rgb * (alpha / ca.a) : ca.rgb * ratio;
    if (clip) { alpha = 0.0; colour = vec3(0.0); }  // clipping keeps the medium (Fig. 6.6)
}

// Light and viewing rays cannot turn by more than ~84 degrees from the sweep direction:
// they must reach the next plane (thesis ch. 7). Directions are bent no further.
// MIN_FORWARD (that cosine) is a macro build.rs defines from src/render/limits.rs.
#ifndef MIN_FORWARD
#error "MIN_FORWARD comes from build.rs (src/render/limits.rs)"
#endif

vec3 plane_point(vec2 uv, float depth) {
    vec2 ndc = uv * 2.0 - 1.0;
    return depth * vec3(ndc.x * P.camera.x * P.camera.y, -ndc.y * P.camera.x, 1.0);
}

vec2 project(vec3 q) {
    vec2 ndc = vec2(q.x / (q.z * P.camera.x * P.camera.y), -q.y / (q.z * P.camera.x));
    return ndc * 0.5 + 0.5;
}

vec3 to_tex(vec3 p) {
    return (P.view_to_tex * vec4(p, 1.0)).xyz;
}

// Scalar value; zero outside the volume box.
float value_at_tex(vec3 t) {
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return 0.0;
    return textureLod(volume, t, 0.0).r;
}

float eta_of(float s) {
    float eta = textureLod(tf, vec2(tf_coord(s), 1.0), 0.0).a;
    // k = 1 returns the transfer function's eta bit for bit.
    return P.refraction.x == 1.0 ? eta : 1.0 + P.refraction.x * (eta - 1.0);
}

// The `field` lever (specialization constant 6): value and grad eta from the field
// texture (render::field), one trilinear fetch, where it is bound.
layout(constant_id = 6) const bool HAVE_FIELD = true;
layout(set = 0, binding = 17) uniform sampler3D field_texture;

// Value and gradient of eta at view-space p (view-space units), by central differences
// one voxel apart (eq. 3.16), eta_tf applied to the neighbours before differencing
// (thesis sect. 5.2): from the field texture, which holds them per voxel, or from seven
// volume fetches and six eta lookups. `eta_may_vary` false says eta is one value all
// around p (the caller's empty-space test): the gradient is then zero, and the
// differences are left out by the loop's trip count, not by a branch (llvmpipe runs both
// sides of a branch but leaves a loop once all its lanes are done; equal etas difference
// to exactly zero, so the result is the same).
void sample_field_where(vec3 p, bool eta_may_vary, out float value, out vec3 grad_eta) {
    vec3 t = to_tex(p);
    vec3 ge;
    if (HAVE_FIELD) {
        if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) {
            value = 0.0;
            grad_eta = vec3(0.0);
            return;
        }
        vec4 f = textureLod(field_texture, t, 0.0);
        value = f.x;
        // eta' = 1 + k (eta_tf - 1): grad eta' = k grad eta_tf.
        ge = P.refraction.x * f.yzw;
    } else {
        vec3 h = 1.0 / P.volume_dims.xyz;
        value = value_at_tex(t);
        ge = vec3(0.0);
        int axes = eta_may_vary ? 3 : 0;
        for (int k = 0; k < axes; ++k) {
            vec3 e = vec3(0.0);
            e[k] = h[k];
            ge[k] = (eta_of(value_at_tex(t + e)) - eta_of(value_at_tex(t - e))) / (2.0 * h[k]);
        }
    }
    // d/d(view) = J^T d/d(tex), J = d(tex)/d(view).
    grad_eta = transpose(mat3(P.view_to_tex)) * ge;
}

void sample_field(vec3 p, out float value, out vec3 grad_eta) {
    sample_field_where(p, true, value, grad_eta);
}

// The exact gradient of the trilinearly interpolated value at view-space p (view-space
// units), from the eight voxels of p's cell fetched without filtering. Where the value
// changes within a voxel or two (a sharp glass surface), central differences a voxel
// apart straddle the whole change and tilt the normal towards the grid axes by ~10°
// (measured on a ball); this is the field's own normal. Zero outside the volume box.
vec3 value_gradient(vec3 p) {
    vec3 t = to_tex(p);
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return vec3(0.0);
    vec3 dims = P.volume_dims.xyz;
    float c[8];
    vec3 f;
    cell_voxels(volume, t, dims, c, f);
    // d/dx, d/dy, d/dz of the trilinear interpolant, per voxel.
    float x00 = mix(c[0], c[1], f.x), x10 = mix(c[2], c[3], f.x);
    float x01 = mix(c[4], c[5], f.x), x11 = mix(c[6], c[7], f.x);
    float dx = mix(mix(c[1] - c[0], c[3] - c[2], f.y), mix(c[5] - c[4], c[7] - c[6], f.y), f.z);
    float dy = mix(x10 - x00, x11 - x01, f.z);
    float dz = mix(x01, x11, f.y) - mix(x00, x10, f.y);
    mat3 jt = transpose(mat3(P.view_to_tex));
    return jt * (vec3(dx, dy, dz) * dims);
}

// Features a frame does not use are switched off at pipeline creation (specialization
// constants 1-4, set by render::refract from the frame's options), so their code costs
// nothing: llvmpipe runs both sides of a branch on a uniform. Each is true exactly when
// the runtime condition it guards can hold, so the images do not change.
layout(constant_id = 1) const bool HAVE_SPECULAR = true;     // P.specular.y > 0
layout(constant_id = 2) const bool HAVE_CLIP = true;         // a clipping plane is set
layout(constant_id = 3) const bool HAVE_REFLECTIONS = true;  // P.refraction.y > 0.5
layout(constant_id = 4) const bool HAVE_SOFT_LIGHT = true;   // softness > 0 (backward)

bool clipped(vec3 p) {
    if (!HAVE_CLIP || dot(P.clip.xyz, P.clip.xyz) == 0.0) return false;
    vec3 w = (P.view_to_world * vec4(p, 1.0)).xyz;
    return dot(P.clip.xyz, w) > P.clip.w;
}

// One step of the ray equation across a change of eta (eq. 4.3 integrated as Snell's law
// for the step): v = eta dx/ds keeps its component tangential to the local interface
// (normal along grad eta) and its length becomes the new eta. Exact for a sharp
// interface crossed within one step whatever the sample distance, and the ray equation
// to first order where eta varies smoothly. Where the normal part would be imaginary the
// ray is totally internally reflected (its normal component flips).
vec3 refract_step(vec3 v, float eta_new, vec3 grad_eta) {
    float eta_old = length(v);
    float g = length(grad_eta);
    if (!(g > 1e-3)) return v * (eta_new / eta_old);
    vec3 n = grad_eta / g;
    float vn = dot(v, n);
    vec3 vt = v - vn * n;
    float disc = eta_new * eta_new - dot(vt, vt);
    if (disc < 0.0) return vt - vn * n;
    return vt + (vn >= 0.0 ? 1.0 : -1.0) * sqrt(disc) * n;
}

// Keep a direction (|v| = eta) inside the sweep's half-space.
vec3 limit_direction(vec3 v) {
    float n = length(v);
    if (!(n > 0.0)) return vec3(0.0, 0.0, 1.0);
    vec3 d = v / n;
    if (d.z < MIN_FORWARD) {
        vec2 lateral = d.xy;
        float l = length(lateral);
        lateral = l > 0.0 ? lateral / l : vec2(1.0, 0.0);
        d = vec3(lateral * sqrt(1.0 - MIN_FORWARD * MIN_FORWARD), MIN_FORWARD);
    }
    return d * n;
}

#endif

// The ray equation in the volume's refractive-index field, in world space: the integrator
// of issue 35's light simulator and view renderer (seed 001, Ihrke et al., eqs. 11-15;
// the thesis' eq. 4.3), with the conventions of the CPU photon tracer (src/photons/mod.rs,
// "Model"), which is its reference in tests/ray_equation.rs.
//
//   d/ds (eta dx/ds) = grad eta, integrated with classical RK4 in (x, v = eta dx/ds) with
//   dx/ds = v / |v|: equal to v / eta on the exact solution (|v| = eta is invariant) and
//   it keeps s an exact arc length, which the attenuation integral needs.
//
// The includer defines, before including this file:
//   RAY_VOLUME   a sampler3D of the value (read unfiltered, texelFetch),
//   RAY_TF       the transfer functions' sampler1DArray (texelFetch; layer 0: colour, opacity;
//                layer 1: medium colour, eta),
//   RAY_HALF     the box's half extent (world units; the box is centred at the origin),
//   RAY_DIMS     the volume's size in voxels (vec3),
//   RAY_REF_STEP the reference step (world units: the smallest voxel side),
//   RAY_ETA_SCALE the refractive-index scale k: eta' = 1 + k (eta_tf - 1),
// and optionally RAY_FIELD (below) and RAY_CUBIC (a bool, usually a specialization
// constant: eta from the cubic B-spline of the values, below; false when not defined).
#ifndef REFRAKT_RAY_EQUATION_GLSL
#define REFRAKT_RAY_EQUATION_GLSL
#ifndef RAY_CUBIC
#define RAY_CUBIC false
#endif
#include "common.glsl"

// Texture coordinates of world point w: t = w / (2 half) + 0.5.
vec3 ray_tex(vec3 w) { return w / (2.0 * RAY_HALF) + 0.5; }

// Filtering is done here from unfiltered fetches, in f32: a GPU's texture filter may
// weigh texels with 8-bit fractions (the Vulkan spec allows it), and differences 0.05
// voxels apart taken from such values would be steps, not slopes.

#ifdef RAY_FIELD
// With RAY_FIELD defined (a sampler3D of the field texture, glsl/field.comp: per voxel the
// value and grad eta_tf by central differences one voxel apart, per unit texture
// coordinate) and RAY_USE_FIELD true (a specialization constant, so the other way is
// compiled out), value and grad eta come from one filtered fetch each: the paper's stored
// refractive-index and gradient volumes (seed 001 sect. 5.1), about a fifteenth of the
// fetches of the differences below and a gradient continuous across cell faces, but a
// surface sharper than a voxel or two is blurred by the one-voxel differences (the glass
// sphere's shadow 1.4 % R off the photon tracer's, measured: tests/light_simulator.rs).
// The light simulator offers it (`RayGradient::FieldTexture`); the probe, held to the
// CPU tracer, does not.
vec4 ray_field(vec3 w) {
    vec3 t = ray_tex(w);
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return vec4(0.0);
    return textureLod(RAY_FIELD, t, 0.0);
}
#endif

// The trilinear interpolant of a cell given as its z = 0 and z = 1 faces (voxels in
// cell_voxels' order) at fraction f: along x, then y, then z. ray_value and ray_eta_grad
// both take it, so their values agree to the bit.
float ray_trilinear4(vec4 z0, vec4 z1, vec3 f) {
    float y0 = mix(mix(z0.x, z0.y, f.x), mix(z0.z, z0.w, f.x), f.y);
    float y1 = mix(mix(z1.x, z1.y, f.x), mix(z1.z, z1.w, f.x), f.y);
    return mix(y0, y1, f.z);
}

// The value at world point w: the trilinear interpolant of the voxels (clamp to edge),
// zero outside the box (as the sweep's value_at_tex and the CPU tracer).
float ray_value(vec3 w) {
#ifdef RAY_FIELD
    if (RAY_USE_FIELD) return ray_field(w).x;
#endif
    vec3 t = ray_tex(w);
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return 0.0;
    float c[8];
    vec3 f;
    cell_voxels(RAY_VOLUME, t, RAY_DIMS, c, f);
    return ray_trilinear4(vec4(c[0], c[1], c[2], c[3]), vec4(c[4], c[5], c[6], c[7]), f);
}

// A transfer function's layer at value s: linear between its TF_SAMPLES samples (the
// post-interpolative lookup of tf_coord).
vec4 ray_tf(float s, int layer) {
    float x = clamp(s, 0.0, 1.0) * float(TF_SAMPLES - 1u);
    int j = min(int(floor(x)), int(TF_SAMPLES) - 2);
    vec4 a = texelFetch(RAY_TF, ivec2(j, layer), 0);
    vec4 b = texelFetch(RAY_TF, ivec2(j + 1, layer), 0);
    return mix(a, b, x - float(j));
}

// eta' = 1 + k (eta_tf - 1) of the transfer function's eta_tf.
float ray_scaled_eta(float eta_tf) {
    return RAY_ETA_SCALE == 1.0 ? eta_tf : 1.0 + RAY_ETA_SCALE * (eta_tf - 1.0);
}

// The cubic B-spline's weights (xyz: per axis) for the four voxels i - 1 .. i + 2 around
// fraction f (x = t dims - 0.5 = i + f), and their derivatives d/df.
void ray_bspline(vec3 f, out vec3 w0, out vec3 w1, out vec3 w2, out vec3 w3, out vec3 d0,
                 out vec3 d1, out vec3 d2, out vec3 d3) {
    vec3 g = 1.0 - f;
    w0 = g * g * g / 6.0;
    w1 = (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0;
    w2 = (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0;
    w3 = f * f * f / 6.0;
    d0 = -0.5 * g * g;
    d1 = 1.5 * f * f - 2.0 * f;
    d2 = -1.5 * f * f + f + 0.5;
    d3 = 0.5 * f * f;
}

// The value at world point w as the cubic B-spline of the voxels (clamp to edge; zero
// outside the box, with a zero gradient) and its gradient per world unit: the CPU
// field's value_grad_cubic (src/photons/field.rs), which the reference renderer and the
// photon tracer take with `use_cubic_eta`. C2, so the refractive index's iso-surfaces
// are smooth where the trilinear field's are corrugated at the voxels' period (each cell
// its own normal: micro-foci that fragment a wavefront and speckle the view through
// glass; docs/NOTES.md, "Cubic η for the eikonal model"). 64 texel fetches, written out per row of four
// along x (no indexed arrays: llvmpipe spills those).
float ray_value_grad_cubic(vec3 w, out vec3 grad) {
    vec3 t = ray_tex(w);
    grad = vec3(0.0);
    if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) return 0.0;
    vec3 xc = t * RAY_DIMS - 0.5;
    ivec3 i = ivec3(floor(xc));
    vec3 f = xc - vec3(i);
    vec3 w0, w1, w2, w3, d0, d1, d2, d3;
    ray_bspline(f, w0, w1, w2, w3, d0, d1, d2, d3);
    vec4 wx = vec4(w0.x, w1.x, w2.x, w3.x), dx = vec4(d0.x, d1.x, d2.x, d3.x);
    ivec3 hi = ivec3(RAY_DIMS) - 1;
    int x0 = clamp(i.x - 1, 0, hi.x), x1 = clamp(i.x, 0, hi.x);
    int x2 = clamp(i.x + 1, 0, hi.x), x3 = clamp(i.x + 2, 0, hi.x);
    float s = 0.0;
    vec3 g = vec3(0.0);
#define RAY_CUBIC_ROW(yy, zz, wy, dy, wz, dz)                                            \
    {                                                                                    \
        int y = clamp(i.y + yy, 0, hi.y), z = clamp(i.z + zz, 0, hi.z);                  \
        vec4 row = vec4(texelFetch(RAY_VOLUME, ivec3(x0, y, z), 0).r,                     \
                        texelFetch(RAY_VOLUME, ivec3(x1, y, z), 0).r,                     \
                        texelFetch(RAY_VOLUME, ivec3(x2, y, z), 0).r,                     \
                        texelFetch(RAY_VOLUME, ivec3(x3, y, z), 0).r);                    \
        float v = dot(wx, row), vx = dot(dx, row);                                       \
        s += wz * wy * v;                                                                \
        g += vec3(wz * wy * vx, wz * dy * v, dz * wy * v);                               \
    }
#define RAY_CUBIC_PLANE(zz, wz, dz)                                                      \
    RAY_CUBIC_ROW(-1, zz, w0.y, d0.y, wz, dz)                                            \
    RAY_CUBIC_ROW(0, zz, w1.y, d1.y, wz, dz)                                             \
    RAY_CUBIC_ROW(1, zz, w2.y, d2.y, wz, dz)                                             \
    RAY_CUBIC_ROW(2, zz, w3.y, d3.y, wz, dz)
    RAY_CUBIC_PLANE(-1, w0.z, d0.z)
    RAY_CUBIC_PLANE(0, w1.z, d1.z)
    RAY_CUBIC_PLANE(1, w2.z, d2.z)
    RAY_CUBIC_PLANE(2, w3.z, d3.z)
#undef RAY_CUBIC_PLANE
#undef RAY_CUBIC_ROW
    grad = g * RAY_DIMS / (2.0 * RAY_HALF);
    return s;
}

// d eta_tf / ds of the transfer function's eta layer at s: its segment's slope, zero
// outside [0, 1] (the CPU's lut_slope).
float ray_tf_eta_slope(float s) {
    if (s < 0.0 || s > 1.0) return 0.0;
    float n = float(TF_SAMPLES - 1u);
    int j = min(int(s * n), int(TF_SAMPLES) - 2);
    return (texelFetch(RAY_TF, ivec2(j + 1, 1), 0).a - texelFetch(RAY_TF, ivec2(j, 1), 0).a) * n;
}

// eta' at world point w.
float ray_eta(vec3 w) {
    if (RAY_CUBIC) {
        vec3 g;
        return ray_scaled_eta(ray_tf(ray_value_grad_cubic(w, g), 1).a);
    }
    return ray_scaled_eta(ray_tf(ray_value(w), 1).a);
}

// grad eta' at w (per world unit): central differences RAY_GRADIENT_STEP voxels apart of
// eta'(value(x)), eta applied before differencing (thesis sect. 5.2), as the CPU tracer
// takes it. They are continuous where the trilinear interpolant's own derivative jumps
// (at every cell face), which suits RK4; the exact derivative (eta_tf' k grad value) was
// tried first and sent a ray that ran 0.02 voxel beside a cell face, along it, 64 mrad
// away from the CPU tracer's (docs/NOTES.md, "The ray equation on the GPU").
const float RAY_GRADIENT_STEP = 0.05;

// eta' (1 + k (eta_tf - 1)) of value s at texture point t, 0 outside the box.
float ray_eta_of(float s, vec3 t) {
    bool inside = !(any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0))));
    return ray_scaled_eta(ray_tf(inside ? s : 0.0, 1).a);
}

// The voxel lines along one axis through a cell's four other-axes corners: the cell's
// own two ends (lo, up), and the line's voxel beyond the cell on w's nearer side; a
// point shifted along that axis whose cell starts `shift` (-1, 0, 1) voxels from w's
// takes its lines' ends from these. Returns the shifted cell's lower (xy) and upper ends.
void ray_shift_lines(vec4 lo, vec4 up, vec4 beyond, int shift, out vec4 a, out vec4 b) {
    a = shift < 0 ? beyond : (shift == 0 ? lo : up);
    b = shift < 0 ? lo : (shift == 0 ? up : beyond);
}

// eta' at w and grad eta' there (the central differences above), from one fetch of the
// cell around w and one more slab of four voxels per axis: 20 texel fetches where seven
// ray_eta calls take 56. Each of the six points w +- h e_k differs from w along axis k
// only, by RAY_GRADIENT_STEP < 0.5 voxel, so it shares w's cell along the other two
// axes and its own cell along k starts at most one voxel from w's: the slab beyond w's
// cell on the side of w's nearer face (index i - 1 below the cell's middle, i + 2 above
// it) is the only other one it can need. Every point's value is interpolated from the
// same clamped voxels, with the same fraction and in the same order as ray_value takes
// it on its own, so the result is the seven lookups' to the bit. Written out per axis
// with no indexed arrays: llvmpipe spills an array indexed by a loop it does not unroll
// to memory, which made a first, looped version slower than the seven lookups.
void ray_eta_grad(vec3 w, out float eta, out vec3 grad) {
    if (RAY_CUBIC) {
        // The spline's own gradient through the transfer function's slope (C2 value,
        // so no differences are needed): grad eta' = k eta_tf'(s) grad s.
        vec3 gs;
        float s = ray_value_grad_cubic(w, gs);
        eta = ray_scaled_eta(ray_tf(s, 1).a);
        grad = RAY_ETA_SCALE * ray_tf_eta_slope(s) * gs;
        return;
    }
#ifdef RAY_FIELD
    if (RAY_USE_FIELD) {
        eta = ray_eta(w);
        // eta' = 1 + k (eta_tf - 1); d/dw = d/dt / (2 half).
        grad = RAY_ETA_SCALE * ray_field(w).yzw / (2.0 * RAY_HALF);
        return;
    }
#endif
    vec3 t = ray_tex(w);
    vec3 xc = t * RAY_DIMS - 0.5;
    ivec3 i = ivec3(floor(xc));
    vec3 f = xc - vec3(i);
    ivec3 hi = ivec3(RAY_DIMS) - 1;
#define RAY_VOXEL(dx, dy, dz) texelFetch(RAY_VOLUME, clamp(i + ivec3(dx, dy, dz), ivec3(0), hi), 0).r
    // The cell's z = 0 and z = 1 faces, (x, y) = (0,0), (1,0), (0,1), (1,1).
    vec4 z0 = vec4(RAY_VOXEL(0, 0, 0), RAY_VOXEL(1, 0, 0), RAY_VOXEL(0, 1, 0), RAY_VOXEL(1, 1, 0));
    vec4 z1 = vec4(RAY_VOXEL(0, 0, 1), RAY_VOXEL(1, 0, 1), RAY_VOXEL(0, 1, 1), RAY_VOXEL(1, 1, 1));
    // The slab beyond the cell along each axis, as an offset from i.
    ivec3 by = ivec3(f.x < 0.5 ? -1 : 2, f.y < 0.5 ? -1 : 2, f.z < 0.5 ? -1 : 2);
    // Along x, lines at (y, z) = (0,0), (1,0), (0,1), (1,1).
    vec4 bx = vec4(RAY_VOXEL(by.x, 0, 0), RAY_VOXEL(by.x, 1, 0), RAY_VOXEL(by.x, 0, 1), RAY_VOXEL(by.x, 1, 1));
    // Along y, lines at (x, z) = (0,0), (1,0), (0,1), (1,1).
    vec4 byy = vec4(RAY_VOXEL(0, by.y, 0), RAY_VOXEL(1, by.y, 0), RAY_VOXEL(0, by.y, 1), RAY_VOXEL(1, by.y, 1));
    // Along z, lines at (x, y) = (0,0), (1,0), (0,1), (1,1).
    vec4 bz = vec4(RAY_VOXEL(0, 0, by.z), RAY_VOXEL(1, 0, by.z), RAY_VOXEL(0, 1, by.z), RAY_VOXEL(1, 1, by.z));
#undef RAY_VOXEL
    eta = ray_eta_of(ray_trilinear4(z0, z1, f), t);

    vec3 h = RAY_GRADIENT_STEP * 2.0 * RAY_HALF / RAY_DIMS;
    vec2 sides[3];  // per axis, eta' at w - h e_k and w + h e_k
    for (int s = 0; s < 2; ++s) {
        float sign = s == 0 ? -1.0 : 1.0;
        vec4 a, b;
        // x: the shifted point's lines along x and its fraction along x.
        {
            vec3 tp = ray_tex(w + vec3(sign * h.x, 0.0, 0.0));
            float xp = tp.x * RAY_DIMS.x - 0.5;
            float ip = floor(xp);
            ray_shift_lines(vec4(z0.x, z0.z, z1.x, z1.z), vec4(z0.y, z0.w, z1.y, z1.w), bx,
                            int(ip) - i.x, a, b);
            float e = ray_eta_of(ray_trilinear4(vec4(a.x, b.x, a.y, b.y), vec4(a.z, b.z, a.w, b.w),
                                                vec3(xp - ip, f.y, f.z)), tp);
            if (s == 0) sides[0].x = e; else sides[0].y = e;
        }
        {
            vec3 tp = ray_tex(w + vec3(0.0, sign * h.y, 0.0));
            float yp = tp.y * RAY_DIMS.y - 0.5;
            float ip = floor(yp);
            ray_shift_lines(vec4(z0.x, z0.y, z1.x, z1.y), vec4(z0.z, z0.w, z1.z, z1.w), byy,
                            int(ip) - i.y, a, b);
            float e = ray_eta_of(ray_trilinear4(vec4(a.x, a.y, b.x, b.y), vec4(a.z, a.w, b.z, b.w),
                                                vec3(f.x, yp - ip, f.z)), tp);
            if (s == 0) sides[1].x = e; else sides[1].y = e;
        }
        {
            vec3 tp = ray_tex(w + vec3(0.0, 0.0, sign * h.z));
            float zp = tp.z * RAY_DIMS.z - 0.5;
            float ip = floor(zp);
            ray_shift_lines(z0, z1, bz, int(ip) - i.z, a, b);
            float e = ray_eta_of(ray_trilinear4(a, b, vec3(f.x, f.y, zp - ip)), tp);
            if (s == 0) sides[2].x = e; else sides[2].y = e;
        }
    }
    grad = vec3(sides[0].y - sides[0].x, sides[1].y - sides[1].x, sides[2].y - sides[2].x) / (2.0 * h);
}

vec3 ray_grad_eta(vec3 w) {
    float eta;
    vec3 g;
    ray_eta_grad(w, eta, g);
    return g;
}

// The attenuation rate per channel (per world unit) of opacity alpha and medium colour m
// (both per reference step): extinction sigma = -ln(1 - alpha) / ref_step plus the
// medium's -ln m / ref_step. An opacity of 1 or a medium of 0 is infinite: the light
// stops.
vec3 ray_rate_of(float alpha, vec3 m) {
    float sigma = -log(max(1.0 - alpha, 0.0));
    return (vec3(sigma) - log(max(m, vec3(0.0)))) / RAY_REF_STEP;
}

// The attenuation rate per channel at w (ray_rate_of of the transfer functions there).
vec3 ray_rate(vec3 w) {
    float s = ray_value(w);
    return ray_rate_of(ray_tf(s, 0).a, ray_tf(s, 1).rgb);
}

// One RK4 step of arc length h from (x, v): the ray equation with dx/ds = v / |v|,
// dv/ds = grad eta. Returns the largest |grad eta| its four stages met (a step-size
// controller's measure: ray_rk4_adaptive).
float ray_rk4(inout vec3 x, inout vec3 v, float h) {
    vec3 k1x = normalize(v), k1v = ray_grad_eta(x);
    vec3 v2 = v + 0.5 * h * k1v;
    vec3 k2x = normalize(v2), k2v = ray_grad_eta(x + 0.5 * h * k1x);
    vec3 v3 = v + 0.5 * h * k2v;
    vec3 k3x = normalize(v3), k3v = ray_grad_eta(x + 0.5 * h * k2x);
    vec3 v4 = v + h * k3v;
    vec3 k4x = normalize(v4), k4v = ray_grad_eta(x + h * k3x);
    x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    return max(max(length(k1v), length(k2v)), max(length(k3v), length(k4v)));
}

// The largest turn, in radians, a controlled step may give a ray (ray_rk4_adaptive).
const float RAY_MAX_KICK = 0.02;

// One RK4 step from (x, v) of at most *h (arc length), shortened where a stage meets a
// gradient that would turn the ray by more than RAY_MAX_KICK within it (|grad eta| h >
// RAY_MAX_KICK eta: a face, or a film thinner than the step), down to h_min; returns the
// step taken and leaves in *h the next step to try (doubled back towards h_max). A fixed
// step that lands one stage inside a film thinner than itself and the others outside
// gives the ray the film's whole gradient times the step: a kick that sends it anywhere
// (speckle where viewing rays cross the glass-floor scene's films; docs/NOTES.md). A film
// the stages all miss is crossed unturned, as a thin parallel film leaves a ray.
float ray_rk4_adaptive(inout vec3 x, inout vec3 v, inout float h, float h_max, float h_min) {
    for (;;) {
        vec3 x1 = x, v1 = v;
        float g = ray_rk4(x1, v1, h);
        if (g * h > RAY_MAX_KICK * length(v) && h > h_min) {
            h = max(0.25 * h, h_min);
            continue;
        }
        x = x1;
        v = v1;
        float taken = h;
        h = min(2.0 * h, h_max);
        return taken;
    }
}

// One RK4 step of time dt of the equi-temporal ray equation (seed 001 eqs. 13-15):
// dx/dt = v / eta^2, dv/dt = grad eta / eta. |dx/dt| = 1 / eta, so a step of dt advances
// every particle by the same optical path dt (eta ds = dt): particles launched on a
// wavefront stay on one (the intensity law, eq. 16, needs that of a stream tube's ends).
void ray_rk4_temporal(inout vec3 x, inout vec3 v, float dt) {
    float e1, e2, e3, e4;
    vec3 g1, g2, g3, g4;
    ray_eta_grad(x, e1, g1);
    vec3 k1x = v / (e1 * e1), k1v = g1 / e1;
    vec3 x2 = x + 0.5 * dt * k1x, v2 = v + 0.5 * dt * k1v;
    ray_eta_grad(x2, e2, g2);
    vec3 k2x = v2 / (e2 * e2), k2v = g2 / e2;
    vec3 x3 = x + 0.5 * dt * k2x, v3 = v + 0.5 * dt * k2v;
    ray_eta_grad(x3, e3, g3);
    vec3 k3x = v3 / (e3 * e3), k3v = g3 / e3;
    vec3 x4 = x + dt * k3x, v4 = v + dt * k3v;
    ray_eta_grad(x4, e4, g4);
    vec3 k4x = v4 / (e4 * e4), k4v = g4 / e4;
    x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

// The optical depth per channel along the chord from a to b (length `len`): two-point
// Gauss-Legendre, exact for rates that are cubic along it.
vec3 ray_optical_depth(vec3 a, vec3 b, float len) {
    const float g = 0.28867513;  // 1 / (2 sqrt 3)
    return 0.5 * len * (ray_rate(mix(a, b, 0.5 - g)) + ray_rate(mix(a, b, 0.5 + g)));
}

#endif

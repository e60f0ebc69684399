// One plane of the refractive plane sweep (thesis ch. 4, Algorithm 1): full-screen draws
// that read the previous plane's state from layer `read_layer` and write this plane's
// into the other layer (the render pass's attachments). Included by sweep.frag
// (FORWARD_LIGHT 0, PASS 0: the thesis' backward light step, light and viewing rays in
// one draw) and by the forward transport's two draws, sweep_light_forward.frag (PASS 1:
// the light rays) and sweep_view_forward.frag (PASS 2: the viewing rays), between which
// light_splat.* deposits the rays' flux on the plane. The compute sweep compiles the same
// file with SWEEP_COMPUTE 1 (sweep_plane_io.glsl: what differs).
//
// By thesis step (chapter 4, Algorithm 1), the functions below and what main() does:
// - light, forward (PASS 1): advance_light_ray, eqs. 4.2-4.4 in Snell sub-steps, with
//   straight_in_clear_space choosing one sub-step where nothing can turn or dim the ray;
//   softness as diffusion of flux between neighbouring rays, diffuse_flux;
// - light, backward (PASS 0): backward_light_step, eqs. 4.4-4.8 (light_at: the bilinear,
//   light-weighted read of the previous plane; the soft kernel of sect. 5.2);
// - viewing rays (PASS 0, 2), in main(): a ray that enters the drawn region late,
//   catch_up_to_plane; the segment from the previous plane, viewing_segment (the
//   preintegration table, eq. 3.19, and the box's faces); its light,
//   segment_light; the face or film it meets, face_met (Fresnel reflection, eq. 4.12) and
//   face_highlight (eqs. 4.9-4.11); Oddy-Willis compositing (eq. 4.13); then
//   advance_viewing_ray to the next plane (eq. 4.3: the face step, the graded Snell step,
//   the thesis' kick).
#if !defined(FORWARD_LIGHT) || !defined(PASS)
#error "define FORWARD_LIGHT and PASS before including sweep_plane.glsl"
#endif
// Bisections locating the middle of a face of glass along its normal (to 1/128 of the
// probes' span, ~0.05 voxels).
#ifndef FACE_BISECTIONS
#define FACE_BISECTIONS 7
#endif
#ifndef LIGHT_SUBSTEPS
#define LIGHT_SUBSTEPS 4
#endif
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_light.glsl"
#include "environment.glsl"
#if FORWARD_LIGHT
#include "sweep_rays.glsl"
#endif

#include "sweep_plane_io.glsl"

#if PASS == 0
SIX_STATE_OUTPUTS;
#define STORE_OUTPUTS(at) STORE_SIX_STATES(at)
#elif PASS == 1
// The light rays' images (the ray texel is the invocation's pixel).
PLANE_OUTPUT(0, out_light_colour);
PLANE_OUTPUT(1, out_light_direction);
#define STORE_OUTPUTS(at) \
    imageStore(rays_flux, at, out_light_colour); \
    imageStore(rays_direction, at, out_light_direction);
#else
PLANE_OUTPUT(0, out_view_position);
PLANE_OUTPUT(1, out_view_direction);
PLANE_OUTPUT(2, out_colour_opacity);
PLANE_OUTPUT(3, out_medium);
#define STORE_OUTPUTS(at) \
    imageStore(view_position, at, out_view_position); \
    imageStore(view_direction, at, out_view_direction); \
    imageStore(colour_opacity, at, out_colour_opacity); \
    imageStore(medium, at, out_medium);
#endif

const float PI = 3.14159265358979;

// Light colour and direction at `uv` of the read layer, bilinearly interpolated with the
// directions weighted by the light they carry: where lit and fully absorbed rays meet (a
// shadow edge, a stopped-down aperture, rays crossing in a caustic), the direction of light
// that is not there must not bend the light that is. Where no light arrives at all, plain
// bilinear weights keep the direction field defined.
void light_at(vec2 uv, uint layer, out vec3 light, out vec3 dir) {
    ivec2 size = STATE_SIZE(light_colour);
    vec2 x = uv * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 t = x - vec2(i);
    ivec2 hi = size - 1;
    light = vec3(0.0);
    vec3 d_plain = vec3(0.0);
    vec3 d_lit = vec3(0.0);
    float lit = 0.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 c = clamp(i + o, ivec2(0), hi);
        float w = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
        vec3 l = READ_PIXEL(light_colour, layer, c).rgb;
        vec3 d = READ_PIXEL(light_direction, layer, c).xyz;
        float lum = dot(l, vec3(0.2126, 0.7152, 0.0722));
        light += w * l;
        d_plain += w * d;
        d_lit += w * lum * d;
        lit += w * lum;
    }
    dir = lit > 1e-6 ? d_lit / lit : d_plain;
}

// Radiance arriving along view-space direction d from outside the volume: the environment
// map (rotated about world up like the composite's) or the constant background.
vec3 environment_radiance(vec3 d) {
    if (P.refraction.z < 0.5) return P.background.rgb;
    vec3 w = mat3(P.view_to_world) * d;
    float r = P.refraction.w;
    w = vec3(cos(r) * w.x - sin(r) * w.z, w.y, sin(r) * w.x + cos(r) * w.z);
    return env_bilinear(reflection_env, env_texel(env_angles(w), textureSize(reflection_env, 0)));
}

float hash(uvec3 v) {
    uint h = v.x * 0x8da6b343u ^ v.y * 0xd8163841u ^ v.z * 0xcb1ab31fu;
    h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
    return float(h & 0xffffu) / 65536.0;
}

// Cook-Torrance Fresnel for unpolarised light (eq. 4.12; the thesis prints the bracket's
// square and (g+c) as (g+2) wrongly). eta_ratio = eta_t / eta_i; total reflection where g
// would be imaginary.
float fresnel(float c, float eta_ratio) {
    float g2 = eta_ratio * eta_ratio - 1.0 + c * c;
    if (g2 <= 0.0) return 1.0;
    float g = sqrt(g2);
    float a = (g - c) / (g + c);
    float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

// Cook-Torrance specular (eqs. 4.9-4.11): GGX D with alpha = roughness^2, Smith-Schlick G
// with k = (roughness + 1)^2 / 8. Returns the reflected fraction of the incident light
// (R_s times n.l).
float specular_term(vec3 n, vec3 l, vec3 v, float eta_ratio) {
    float nl = dot(n, l), nv = dot(n, v);
    if (nl <= 0.0 || nv <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float nh = max(dot(n, h), 0.0);
    float r = P.specular.x;
    float a2 = r * r * r * r;
    float den = nh * nh * (a2 - 1.0) + 1.0;
    float D = a2 / (PI * den * den);
    float k = (r + 1.0) * (r + 1.0) / 8.0;
    float G = (nl / (nl * (1.0 - k) + k)) * (nv / (nv * (1.0 - k) + k));
    float F = fresnel(max(dot(v, h), 0.0), eta_ratio);
    return D * F * G / (4.0 * nv);
}

// Fresnel reflectance of a face between eta_a and eta_b for a ray whose v = eta dx/ds has
// the tangential part vt (kept across the face, Snell): F is the same both ways through a
// face (reciprocity), from the angle on its low side; 1 beyond the critical angle.
float face_fresnel(float vt, float eta_a, float eta_b) {
    float lo = min(eta_a, eta_b), hi = max(eta_a, eta_b);
    float sin_lo = vt / lo;
    if (sin_lo >= 1.0) return 1.0;
    return fresnel(sqrt(1.0 - sin_lo * sin_lo), hi / lo);
}

// The part of the straight segment a -> b (view space) inside the volume box, as the
// fractions [t0, t1] of the way from a to b (t1 <= t0: it misses the box).
vec2 box_span(vec3 a, vec3 b) {
    vec3 ta = to_tex(a);
    vec3 d = to_tex(b) - ta;
    d = mix(d, vec3(1e-20), lessThan(abs(d), vec3(1e-20)));   // parallel to a face
    vec3 t_lo = -ta / d, t_hi = (1.0 - ta) / d;
    vec3 t_in = min(t_lo, t_hi), t_out = max(t_lo, t_hi);
    return vec2(max(max(t_in.x, t_in.y), max(t_in.z, 0.0)),
                min(min(t_out.x, t_out.y), min(t_out.z, 1.0)));
}

// Smallest change of eta treated as a face of glass (reflection, highlight): below it,
// noise in a medium (see the viewing rays).
const float MIN_FACE_STEP = 0.02;
// A viewing ray turns by the face step (below) with the weight smoothstep(FACE_STEP_LO,
// FACE_STEP_HI, the step of eta between the probes) and by the graded kick with the rest.
const float FACE_STEP_LO = 0.06;
const float FACE_STEP_HI = 0.1;

// A film between two probes of value v_a and v_b, eta e_a and e_b: eta over the values
// between them (layer 2 of the preintegration table) rises above both ends (or falls
// below both) by MIN_FACE_STEP or more. Returns (1 if so, else 0; the value where the
// film peaks; its eta). See "A film" in main().
layout(constant_id = 7) const bool HAVE_FILMS = true;   // eta has an interior extremum
vec3 film_between(float v_a, float v_b, float e_a, float e_b) {
    if (!HAVE_FILMS) return vec3(0.0);
    vec4 t = textureLod(preint, vec3(preint_coord(v_a, v_b), 2.0), 0.0);
    float k = P.refraction.x;   // eta' = 1 + k (eta - 1), k >= 0 keeps the order
    float top = 1.0 + k * (t.x - 1.0), bottom = 1.0 + k * (t.z - 1.0);
    if (top >= max(e_a, e_b) + MIN_FACE_STEP) return vec3(1.0, t.y, top);
    if (bottom <= min(e_a, e_b) - MIN_FACE_STEP) return vec3(1.0, t.w, bottom);
    return vec3(0.0);
}

// The light chained through a surface's skin (see the viewing rays below), kept in the
// medium buffer's .w: 0 = none; else 64 q + 32 + log2(luminance), q = the skin depth
// crossed so far in sixteenths of a reference step (up to 63), the luminance from 2^-32
// to 2^31, log-coded so a caustic's light keeps its precision (~2e-4 relative).
const float CHAIN_DEPTH = 4.0;  // reference steps of depth (along the gradient) a chain runs
float chain_encode(float light, float depth) {
    float l = clamp(log2(max(light, 1e-30)) + 32.0, 0.0, 63.99);
    return min(round(depth * 16.0), 63.0) * 64.0 + max(l, 1e-3);
}
bool chain_decode(float code, out float light, out float depth) {
    float q = floor(code / 64.0);
    float l = code - q * 64.0;
    depth = q / 16.0;
    light = l <= 1e-2 ? 0.0 : exp2(l - 32.0);
    return code > 0.0;
}

// Empty space (render::value_ranges): per brick of VALUE_BRICK^3 voxels, the least and
// greatest value a sample within one brick of it can read. The `clear` lever
// (specialization constant 8) says whether the passes use it.
layout(set = 0, binding = 19) uniform sampler3D value_ranges;
layout(constant_id = 8) const bool CLEAR_SPACE = true;

// The range of values a sample within one brick of volume texture coordinate t can read
// (t may lie outside the box: its nearest brick's range).
vec2 values_near(vec3 t) {
    ivec3 grid = textureSize(value_ranges, 0);
    ivec3 b = clamp(ivec3(floor(t * P.volume_dims.xyz / float(VALUE_BRICK))), ivec3(0), grid - 1);
    return texelFetch(value_ranges, b, 0).xy;
}

// Whether eta may differ between the samples a voxel either side of view-space p (the
// central differences of sample_field_where): false where every value they can read has
// one eta (layer 2 of the preintegration table: the extremes of eta between two values;
// a sample outside the box reads 0).
bool eta_may_vary_near(vec3 p) {
    // (With the field texture, sample_field_where reads the gradient and ignores this:
    // the constant folds the test's two fetches away.)
    if (!CLEAR_SPACE || HAVE_FIELD) return true;
    vec3 t = to_tex(p);
    vec2 r = values_near(t);
    vec3 h = 1.0 / P.volume_dims.xyz;
    bool inside = all(greaterThanEqual(t - h, vec3(0.0))) && all(lessThanEqual(t + h, vec3(1.0)));
    if (!inside) r = vec2(min(r.x, 0.0), max(r.y, 0.0));
    if (r.y <= r.x) return false;   // one value throughout
    vec4 eta = textureLod(preint, vec3(preint_coord(r.x, r.y), 2.0), 0.0);  // max, -, min, -
    return eta.x - eta.z > 0.0;
}

#if PASS == 1

// Whether a light ray's straight step from p along unit direction d to the next plane
// meets nothing that turns or dims it differently in one sub-step than in LIGHT_SUBSTEPS:
// every value it can read (the dilated range of the brick it starts in; the step moves
// at most one brick along each axis; a step that is not wholly inside the box also meets
// the outside's value 0, value_at_tex) is the same, or the transfer functions give all of
// them no opacity, a white medium and one eta (layer 2 of the preintegration table holds
// the extremes of eta between two values). Then nothing refracts it (refract_step keeps
// |v| = eta), and the attenuation (none, or a homogeneous medium's) composes exactly over
// the whole step (eq. 4.4). The table's bilinear filtering mixes neighbouring ranges in,
// which can only make the test fail where it could have passed.
bool straight_in_clear_space(vec3 p, vec3 d, float ds) {
    if (!CLEAR_SPACE || !(d.z >= MIN_FORWARD)) return false;
    vec3 dims = P.volume_dims.xyz;
    vec3 t0 = to_tex(p), t1 = to_tex(p + d * (ds / d.z));
    vec3 run = abs(t1 - t0) * dims;   // voxels per axis
    if (any(greaterThan(run, vec3(float(VALUE_BRICK))))) return false;
    vec2 r = values_near(t0);
    // The box is convex: a step with both ends inside stays inside; one with both ends
    // beyond the same face of it meets only the outside.
    vec3 lo = min(t0, t1), hi = max(t0, t1);
    bool inside = all(greaterThanEqual(lo, vec3(0.0))) && all(lessThanEqual(hi, vec3(1.0)));
    bool outside = any(lessThan(hi, vec3(0.0))) || any(greaterThan(lo, vec3(1.0)));
    if (outside) return true;
    if (!inside) r = vec2(min(r.x, 0.0), max(r.y, 0.0));
    if (r.y <= r.x) return true;   // one value throughout
    vec2 c = preint_coord(r.x, r.y);
    vec4 eta = textureLod(preint, vec3(c, 2.0), 0.0);      // max eta, -, min eta, -
    float opacity = textureLod(preint, vec3(c, 0.0), 0.0).a;
    vec3 m = textureLod(preint, vec3(c, 1.0), 0.0).rgb;
    return opacity <= 0.0 && all(greaterThanEqual(m, vec3(1.0))) && eta.x - eta.z <= 0.0;
}

#if SOFT_LIGHT
// Softness as diffusion of flux between neighbouring rays: each ray hands the fraction
// w of its flux to each of its four neighbours `stride` rays away and receives theirs.
// The same w everywhere makes the exchange symmetric, so the total is conserved
// exactly; a missing neighbour (grid edge) or a dropped one (direction zero: it
// carries nothing on) hands the share back to the ray itself, and a dropped ray
// takes none (it kept diffused flux away from the live rays for good: 1.3 % of the
// power behind a ball lens, measured).
// Per plane this adds the variance of the thesis' soft-shadow kernel (sect. 5.2), so
// penumbrae widen with the distance behind an occluder.
// `flux` is ray r's (grid cell `ray`, v = lv.xyz) on the previous plane; returns what it
// carries on after the exchange.
vec3 diffuse_flux(ivec2 ray, int r, vec4 lv, vec3 flux) {
    uint R = pc.read_layer;
    float w = P.transport.y;
    int stride = int(P.transport.z);
    vec3 gathered = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        ivec2 o = (k < 2 ? ivec2(k == 0 ? stride : -stride, 0)
                         : ivec2(0, k == 2 ? stride : -stride));
        ivec2 c = ray + o;
        int rc = ray_exists(c) ? ray_index(c) : r;
        bool live = ray_exists(c) && dot(READ_RAY(rays_direction, R, rc).xyz,
                                         READ_RAY(rays_direction, R, rc).xyz) > 0.0;
        gathered += live ? READ_RAY(rays_flux, R, rc).rgb : flux;
    }
    return dot(lv.xyz, lv.xyz) > 0.0 ? (1.0 - 4.0 * w) * flux + w * gathered : vec3(0.0);
}
#endif

// LIGHT_SUBSTEPS sub-steps to this plane, each advancing depth by ds / LIGHT_SUBSTEPS
// along the ray's current direction: attenuated over its own length (eq. 4.4), then
// turned by a Snell step with the interface normal at its midpoint. A curved interface
// crossed within one plane spacing turns the ray by the normals along its way, and a
// ray totally reflected mid-plane moves on in its reflected direction, staying in the
// glass (advancing it along the old direction put it beyond the face, where the next
// sub-step reflected it back: an even number of reflections let 10 % of the light
// through a wedge past the critical angle, measured).
//
// Advances the light ray whose state on the previous plane is lc, lv (flux, view x; v,
// view y), carrying `flux`, to this plane: its flux there, its v (zero: dropped) and its
// point.
void advance_light_ray(vec4 lc, vec4 lv, inout vec3 flux, out vec3 v_new, out vec3 p_new) {
    float ds = P.planes.y;
    float ref_step = P.planes.w;
    vec3 p_step = vec3(lc.w, lv.w, pc.depth - ds);
    v_new = lv.xyz;
    float f_step = value_at_tex(to_tex(p_step));
    bool leaves = false;
    // A film on the ray's way (see "A film" in the viewing rays): the values 2.5
    // reference steps before and beyond this plane step, along the ray, are the plateaus
    // either side; where eta between them peaks (or dips) past both, the ray crosses a
    // skin the classification made, and turns as between the plateaus, not into and out
    // of the skin. (Turned by a skin thinner than a substep on some planes only, the
    // rays shifted their deposits: the demo's lit floor striped faintly, row to row 1.91
    // of display luminance against 1.46 without refracting light at all.)
    // (A dropped ray has v = 0: it looks straight ahead here, and the loop drops it again.)
    vec3 d_in = dot(lv.xyz, lv.xyz) > 0.0 ? normalize(lv.xyz) : vec3(0.0, 0.0, 1.0);
    float reach = 2.5 * ref_step;
    float v_before = value_at_tex(to_tex(p_step - reach * d_in));
    float v_after = value_at_tex(to_tex(p_step + (ds / max(d_in.z, MIN_FORWARD) + reach) * d_in));
    float e_before = eta_of(v_before), e_after = eta_of(v_after);
    vec3 film = film_between(v_before, v_after, e_before, e_after);
    // In clear or homogeneous space one sub-step is the same step (see
    // straight_in_clear_space). A loop's trip count, not a branch: llvmpipe runs both
    // sides of a branch but leaves a loop once all its lanes are done, and light rays
    // side by side cross the same space (on a GPU the warp's lanes agree likewise).
    int substeps = straight_in_clear_space(p_step, d_in, ds) ? 1 : LIGHT_SUBSTEPS;
    float dz = ds / float(substeps);
    for (int k = 0; k < substeps; ++k) {
        vec3 d = normalize(v_new);
        if (!(dot(v_new, v_new) > 0.0) || !(d.z >= MIN_FORWARD)) {
            leaves = true;
            break;
        }
        vec3 q = p_step + d * (dz / d.z);
        float f_q = value_at_tex(to_tex(q));
        vec3 seg_c; float seg_a; vec3 seg_m;
        segment(f_step, f_q, length(q - p_step) / ref_step, clipped(q), seg_c, seg_a, seg_m);
        flux *= (1.0 - seg_a) * seg_m;
        // The interface normal is the value's gradient: refract_step needs only its
        // direction (either sign), and level sets of the value are where eta changes.
        vec3 normal = value_gradient(0.5 * (p_step + q));
        float eta_q = eta_of(f_q);
        if (film.x > 0.0) eta_q = (f_q < film.y) == (v_before < film.y) ? e_before : e_after;
        v_new = refract_step(v_new, eta_q, normal);
        p_step = q;
        f_step = f_q;
    }
    p_new = vec3(p_step.xy, pc.depth);
    if (leaves || !(v_new.z >= MIN_FORWARD * length(v_new))) {
        // Turned back or more than ~84° from the sweep direction (total internal
        // reflection, a grazing exit): this light leaves what the sweep can follow. It is
        // dropped and counted, never re-aimed: a clamped direction would deposit its flux
        // where it cannot go.
        // Its direction becomes zero: the mark of a dropped ray, whose position is
        // stale from here on (a cell with such a corner deposits as a box,
        // light_splat_ray.glsl), and which stays dropped (no direction to step along).
        if (max(flux.r, max(flux.g, flux.b)) > 0.0) count_clamp(1u);
        flux = vec3(0.0);
        v_new = vec3(0.0);
        p_new = vec3(lc.w, lv.w, pc.depth);
    }
    if (any(isnan(flux)) || any(isinf(flux))) flux = vec3(0.0);
}
#endif

#if PASS != 1
// A pixel's first plane in the drawn region (render::refract::region): its ray is
// still where the setup put it, on plane 0, and has crossed empty space since (the
// region bounds the box up to beyond this plane). Straight on to this plane, as the
// full-screen sweep would have moved it; the value behind it stays the empty space's.
// Its skin chain (below) starts as the full-screen sweep's would have, at the light
// before any matter: the light of the previous plane where the ray is now.
//
// Moves vp (the ray's point, direction vd) on to this plane where it is a plane or more
// behind, and starts its skin chain there.
void catch_up_to_plane(inout vec3 vp, vec3 vd, inout float chain) {
    uint R = pc.read_layer;
    float ds = P.planes.y;
    if (vp.z < pc.depth - 0.5 * ds) {   // a whole plane or more behind
        // Plane by plane, as the full-screen sweep steps it (the same arithmetic, so the
        // same rounding: in a noisy medium a ray that lands a rounding error elsewhere
        // may take another turn).
        vec3 d0 = normalize(vd);
        for (int k = 0; k < int(P.planes.z) && vp.z < pc.depth - 0.5 * ds; ++k) {
            vp = vp + d0 * (ds / d0.z);
        }
#if FORWARD_LIGHT
        vec3 l0 = READ_BUFFER(irradiance, R, project(vp)).rgb;
#else
        vec3 l0 = READ_BUFFER(light_colour, R, project(vp)).rgb;
#endif
        if (P.unlit == 0u) chain = chain_encode(dot(l0, vec3(0.2126, 0.7152, 0.0722)), 0.0);
    }
}

// The viewing ray's segment from the previous plane (value v_prev) to vp on this plane
// (value f_v), seg_len long along dir, integrated from the preintegration table (eq.
// 3.19): its premultiplied colour c, opacity a and medium m.
//
// Where the volume's data ends (a floor cut by the box's side, a scan cut through
// the body) the value steps at the box face, not along the segment: integrate
// only the part inside, from the value on the face. (Preintegrated as a ramp from
// the empty outside, the face's opacity depended on where the planes cut it: the
// floors' cut sides were hatched at the plane spacing.)
void viewing_segment(vec3 vp, vec3 dir, float seg_len, float v_prev, float f_v, out vec3 c,
                     out float a, out vec3 m) {
    float ref_step = P.planes.w;
    vec2 span = box_span(vp - dir * seg_len, vp);
    float v_front = v_prev, v_back = f_v, inside = max(span.y - span.x, 0.0);
    if (inside > 0.0 && (span.x > 0.0 || span.y < 1.0)) {
        float t_face = span.x > 0.0 ? span.x : span.y;
        vec3 on_face = clamp(to_tex(vp - dir * (seg_len * (1.0 - t_face))), 0.0, 1.0);
        float v_face = textureLod(volume, on_face, 0.0).r;
        if (span.x > 0.0) v_front = v_face; else v_back = v_face;
    }
    segment(v_front, v_back, inside * seg_len / ref_step, clipped(vp), c, a, m);
}

// The light of the matter inside the segment, not of the plane before it (the
// cause of banding at the plane spacing on lit surfaces; docs/NOTES.md).
//
// (1) Within the segment the light crosses the same matter as the viewing ray
// on its way to each point. Locally the matter is a layer across the value
// gradient n, so the light's optical depth to a point is r times the viewing
// ray's, r = |n.v| / |n.l| (in a homogeneous medium, the two path lengths back
// to the plane: v_z / l_z). Integrating e^-t (view) e^-rt (light) over the
// segment's optical depth weights its emission by (1 - (1-a)^(1+r)) / ((1+r) a):
// 1 for clear matter, 1 / (1 + r) for an opaque one, however the planes cut it.
//
// For the segment from the previous plane (value v_prev there, chain code chain_prev) to
// this plane (value f_v, smoothed normal n_here), dir the viewing ray's direction and ldir
// the light's, opacity a and seg_len long: c, its colour (eq. 3.19), becomes the part the
// light lights, c_ambient the part the ambient level lights, and i_d, the plane's light at
// the segment's front, the light its matter receives. Returns the chain code for the next
// plane.
float segment_light(vec3 dir, vec3 ldir, float f_v, float v_prev, vec3 n_here, float a,
                    float seg_len, float chain_prev, inout vec3 c, out vec3 c_ambient,
                    inout vec3 i_d) {
    float ref_step = P.planes.w;
    float r = dir.z / max(ldir.z, 1e-3);
    float across = 1.0;   // depth crossed per unit of path, along the gradient
    // (The layer's normal is the Sobel-smoothed one: in a noisy medium the plain
    // central difference points anywhere; on the lung CT without refraction the
    // median residual fell from 8.1 to 8.0 of 255 with it.)
    bool layered = abs(f_v - v_prev) > 1e-4 && dot(n_here, n_here) > 1e-12;
    if (layered) {
        vec3 n = normalize(n_here);
        across = abs(dot(n, dir));
        // Not for light grazing the layers: the ratio is a flat layer's, as wide as
        // the light's path in it, which grows without bound as n.l -> 0. (Bounded
        // at 1e-3, r reached 1000 where noise or a fog's curved layers put n.l
        // near 0, and single pixels along a fog's terminator lost most of their
        // light: speckle, and contour lines over the supernova's noisy shells;
        // tests/baselines.rs.) Bounded as the sweep bounds directions, at
        // MIN_FORWARD (84 degrees from the normal), so r <= 10: the weight stays
        // continuous in n.l, and a surface lit at up to 84 degrees keeps its law.
        r = across / max(abs(dot(n, ldir)), MIN_FORWARD);
    }
    float k = 1.0 + r;
    // (The ambient level lights the whole segment, unoccluded: it keeps c.)
    c_ambient = c;
    c *= a > 1e-4 ? (1.0 - pow(1.0 - a, k)) / (k * a) : 1.0 - 0.5 * r * a;
    // (2) Through a surface's skin the light at the segment's front is chained from
    // the previous segment (its light times (1-a)^r, the same layer model), not
    // read from this plane: the plane's light is resolved at its pixel pitch (and,
    // forward, on the rays' boxes), so across a skin thinner than a pixel it mixes
    // lit and shadowed matter. The chain starts at the plane light of the last
    // segment before the matter and runs CHAIN_DEPTH reference steps deep into it
    // (along the gradient, so a grazing view follows a skin as far as a steep one);
    // deeper, in clear space and in homogeneous matter, the plane's light rules, so
    // shadows cast by other matter are seen (within a skin they are not: the
    // chain's limit). The chain lives in medium.w (chain_decode).
    float chained_light, chained_depth;
    bool matter = a > 1e-3;
    bool have_chain = chain_decode(chain_prev, chained_light, chained_depth);
    if (matter && have_chain && layered && chained_depth < CHAIN_DEPTH) {
        float have = dot(i_d, vec3(0.2126, 0.7152, 0.0722));
        i_d = have > 1e-6 ? i_d * (chained_light / have)
                          : P.light_colour.rgb * chained_light;
    }
    float next = dot(i_d, vec3(0.2126, 0.7152, 0.0722)) * pow(1.0 - a, r);
    float depth = matter ? chained_depth + seg_len * across / ref_step : 0.0;
    return chain_encode(next, depth);
}

// The film of face_met (below) met in this segment, if the segment passes its peak: its
// Fresnel reflection and its orientation and eta ratio for the highlight (left as they
// are where no film is met). film = film_between(v_minus, v_plus, e_minus, e_plus) of the
// probes either side; n points to higher eta.
void film_reflection(vec3 film, float v_minus, float v_plus, float e_minus, float e_plus,
                     float v_prev, float f_v, vec3 n, vec3 dir, vec3 vd, bool reflections,
                     inout float reflected, inout vec3 reflected_dir, inout vec3 highlight_n,
                     inout float highlight_ratio) {
    float s_film = film.y;
    bool from_minus = (v_minus < s_film) == (v_prev < s_film);
    float eta_1 = from_minus ? e_minus : e_plus;   // the side the ray comes from
    float eta_2 = from_minus ? e_plus : e_minus;
    if ((v_prev < s_film) != (f_v < s_film) && abs(eta_2 - eta_1) >= MIN_FACE_STEP) {
        vec3 nf = dot(n, dir) < 0.0 ? -n : n;
        float f = face_fresnel(length(vd - dot(vd, nf) * nf), eta_1, eta_2);
        // Beyond the critical angle nothing is looked up, as for a face (face_reflection).
        if (reflections && f < 1.0) {
            reflected = f;
            reflected_dir = reflect(normalize(vd), nf);
        }
        highlight_n = nf;
        highlight_ratio = eta_2 / eta_1;
    }
}

// The face of face_met (below) met in this segment (eta from eta_prev to eta_here, the
// probes' eta e_minus and e_plus; n points to higher eta): its Fresnel reflection (eq.
// 4.12) and its orientation and eta ratio for the highlight (left as they are where the
// segment does not cross the face's middle).
void face_reflection(float eta_prev, float eta_here, float e_minus, float e_plus, vec3 n,
                     vec3 vd, bool reflections, inout float reflected,
                     inout vec3 reflected_dir, inout vec3 highlight_n,
                     inout float highlight_ratio) {
    float d_eta = eta_here - eta_prev;
    // A face: where eta steps (a one-voxel ramp between plateaus) the viewing ray
    // meets a surface of glass once, whatever the sample distance and however the
    // planes cut the ramp: in the segment where eta passes the middle of the step,
    // whose plateaus are found a few voxels either side along the normal. There it
    // reflects (Fresnel) and shows the highlight, both with the whole step's F. (Per
    // plane from consecutive eta samples, the highlight's F depended on how much of
    // the ramp a plane happened to straddle: rings on glass at the plane spacing; and
    // the sum of each segment's own small F is a fraction of the face's, as for a
    // graded face, which physically reflects little.)
    float eta_lo = min(min(eta_here, eta_prev), e_minus);
    float eta_hi = max(max(eta_here, eta_prev), e_plus);
    float eta_mid = 0.5 * (eta_lo + eta_hi);
    // A face is a step of at least MIN_FACE_STEP: in noise (a scanned or
    // simulated medium) eta wobbles about its plateau and the smoothed gradient
    // points anywhere, so a wobble seen at a grazing angle to that random normal
    // reflected nearly everything (white speckles through red wine, measured).
    if ((eta_prev < eta_mid) != (eta_here < eta_mid) && eta_hi - eta_lo >= MIN_FACE_STEP) {
        // The angle of incidence on the face's low-eta side, from the tangential
        // part of v = eta dx/ds, which crossing the face keeps (Snell); the ray's
        // own direction is already partly turned inside the ramp. F is the same
        // both ways through the face (reciprocity) short of total reflection.
        vec3 vt = vd - dot(vd, n) * n;
        bool entering = d_eta > 0.0;
        float sin_lo = length(vt) / eta_lo;
        // Fresnel reflection (the F of eq. 4.12, unpolarised): the reflected part
        // sees the environment (or the background) in the mirrored direction,
        // weighted by (1 - A) M like everything composited (eq. 4.13), and the ray
        // goes on with the rest (folded into A, so what lies behind is seen through
        // 1 - F). Not occluded: the mirrored direction is not traced through the
        // volume (like the thesis' highlights, ch. 8). Beyond the critical angle
        // the ray itself is the reflected light (its Snell step turns it back), so
        // nothing is looked up. (Looking the environment up with F = 1 there and
        // ending the ray was tried: no visible difference on the wine glass.)
        if (reflections && sin_lo < 1.0) {
            reflected = face_fresnel(length(vt), eta_lo, eta_hi);
            // Mirror the direction the ray had on the side it came from.
            float eta_in = entering ? eta_lo : eta_hi;
            float vn = sqrt(max(eta_in * eta_in - dot(vt, vt), 0.0));
            vec3 incident = (vt + (dot(vd, n) >= 0.0 ? vn : -vn) * n) / eta_in;
            reflected_dir = reflect(incident, n);
        }
        highlight_n = n;
        highlight_ratio = entering ? eta_hi / eta_lo : eta_lo / eta_hi;
    }
}

// The face or film of glass a viewing ray meets in this plane's segment (from its
// previous point, value v_prev and eta eta_prev, to vp, value f_v and eta eta_here;
// direction dir, v = vd, seg_len long, n_here the smoothed normal at vp): the fraction
// it reflects (eq. 4.12) and the mirrored direction, and for the highlight the face's
// orientation (zero where none is met) and eta ratio. Not only where eta changes between
// the two samples: a film of glass may lie between samples of equal eta, or hold both.
void face_met(vec3 vp, vec3 vd, vec3 dir, float seg_len, vec3 n_here, float v_prev,
              float eta_prev, float f_v, float eta_here, bool reflections,
              out float reflected, out vec3 reflected_dir, out vec3 highlight_n,
              out float highlight_ratio) {
    float ref_step = P.planes.w;
    float d_eta = eta_here - eta_prev;
    vec3 mid = vp - 0.5 * seg_len * dir;
    vec3 g = n_here;   // the face's orientation (see below)
    vec3 n = dot(g, g) > 1e-12 ? normalize(g) : dir;
    if (dot(n, dir) * d_eta < 0.0) n = -n;   // n points to higher eta
    float h = 0.5 * seg_len + 2.5 * ref_step;
    float v_minus = value_at_tex(to_tex(mid - h * n));
    float v_plus = value_at_tex(to_tex(mid + h * n));
    float e_minus = eta_of(v_minus), e_plus = eta_of(v_plus);
    // A film: where the value ramps between two matters through a band of eta
    // that belongs to neither, eta rises (or falls) and returns between the
    // probes. The demo floor's edge passes through the glass's band (0.45-0.6):
    // a 1D transfer function dresses the floor in a skin of glass a fraction of a
    // voxel thick. A plane sample lands in such a skin on some rows and not on
    // others, so judged from the samples it reflected on every other row: the
    // floor's shadow was striped +-20 % at the plane spacing. Such a skin is the
    // classification's, not the scene's (a glass sphere over a white floor has
    // no glass on the floor; wine touches its glass with no air between), and it
    // is thinner than a face as the sweep knows faces, by their plateaus either
    // side (the viewing ray's turn below sees only those). So a film is one face,
    // between the probes' plateaus (none where both are alike, as on the floor),
    // met in the one segment whose values pass the film's peak: found in value
    // space (the extremes of eta between the probes' values, layer 2 of the
    // preintegration table), it is the same whatever the planes. (Reflecting it as
    // the two faces of a glass film, 1 - (1 - F1)(1 - F2), was tried: uniform on
    // the floor, but where wine meets its glass the air the ramp passes through
    // reflected up to total reflection, speckling the wine.)
    vec3 film = film_between(v_minus, v_plus, e_minus, e_plus);
    // The face or film met here, for its highlight (after both): its orientation
    // and eta ratio.
    highlight_n = vec3(0.0);
    highlight_ratio = 1.0;
    // Its reflection: the fraction reflected and the mirrored direction (looked up
    // once, after both: llvmpipe would run a lookup in each branch).
    reflected = 0.0;
    reflected_dir = vec3(0.0, 0.0, -1.0);
    if (film.x > 0.0) {
        film_reflection(film, v_minus, v_plus, e_minus, e_plus, v_prev, f_v, n, dir, vd,
                        reflections, reflected, reflected_dir, highlight_n, highlight_ratio);
    } else if (abs(d_eta) > 1e-4) {
        face_reflection(eta_prev, eta_here, e_minus, e_plus, n, vd, reflections, reflected,
                        reflected_dir, highlight_n, highlight_ratio);
    }
}

// The highlight of the light on the face (eqs. 4.9-4.11), lit by the light
// that meets the face: read on the segment's front plane, moved off the face
// along that plane to the side the light comes from. (Near the line where the
// plane cuts the face its light is a blur of the refracted and the
// unrefracted, whose mix depended on how the planes fell: the highlight
// banded at the plane spacing.)
//
// The face's orientation face_n and eta ratio come from face_met; the segment ends at vp,
// seg_len long along dir; ldir is the light's direction where the segment starts.
vec3 face_highlight(vec3 vp, vec3 dir, float seg_len, vec3 ldir, vec3 face_n, float ratio,
                    uint R) {
    float ref_step = P.planes.w;
    vec3 n = face_n;
    vec3 front = vp - dir * seg_len;
    vec3 along = vec3(n.xy, 0.0);
    float la = length(along);
    float side = dot(ldir, n) > 0.0 ? -1.0 : 1.0;
    vec3 off = la > 1e-3 ? along / la * side * (2.5 * ref_step / max(la, 0.3))
                         : vec3(0.0);
    vec2 uv_face = project(front + off);
#if FORWARD_LIGHT
    vec3 i_face = READ_BUFFER(irradiance, R, uv_face).rgb;
    vec3 l_face = splatted_direction(READ_BUFFER(irradiance_direction, R, uv_face));
#else
    vec3 i_face = READ_BUFFER(light_colour, R, uv_face).rgb;
    vec3 l_face = normalize(READ_BUFFER(light_direction, R, uv_face).xyz);
#endif
    vec3 v = -dir;
    vec3 nv = dot(n, v) < 0.0 ? -n : n;
    return P.specular.y * specular_term(nv, -l_face, v, ratio) * i_face;
}

// The face advance_viewing_ray (below) steps through: its middle on the normal line
// through `centre` (nn points to higher eta; the probes at +-hs read eta_hi and eta_lo),
// found by bisection to eta_mid, and how sharp it is: 1 where most of the step lies
// within 1.5 reference steps of the middle with plateaus at the probes, 0 for a graded
// ramp. With face_used false the bisection and the probes run no trips (see the caller).
float face_sharpness(vec3 centre, vec3 nn, float hs, float eta_lo, float eta_hi,
                     float eta_mid, float face_step, bool face_used, out vec3 face) {
    float ref_step = P.planes.w;
    // The face's middle on the normal line through the centre.
    float s0 = -hs, s1 = hs;
    int bisections = face_used ? FACE_BISECTIONS : 0;
    for (int k = 0; k < bisections; ++k) {
        float s = 0.5 * (s0 + s1);
        if (eta_of(value_at_tex(to_tex(centre + s * nn))) >= eta_mid) s1 = s; else s0 = s;
    }
    face = centre + 0.5 * (s0 + s1) * nn;
    // Eta 1.5 reference steps either side of the middle (k = 0, 1: the step across
    // the face) and 1.5 beyond either probe (k = 2, 3: further out).
    float e_across_hi = 0.0, e_across_lo = 0.0, e_further_hi = 0.0, e_further_lo = 0.0;
    int probes = face_used ? 4 : 0;
    for (int k = 0; k < probes; ++k) {
        float side = (k & 1) == 0 ? 1.0 : -1.0;
        vec3 from = k < 2 ? face : centre;
        float reach = k < 2 ? 1.5 * ref_step : hs + 1.5 * ref_step;
        float e = eta_of(value_at_tex(to_tex(from + side * reach * nn)));
        e_across_hi = k == 0 ? e : e_across_hi;
        e_across_lo = k == 1 ? e : e_across_lo;
        e_further_hi = k == 2 ? e : e_further_hi;
        e_further_lo = k == 3 ? e : e_further_lo;
    }
    float across = e_across_hi - e_across_lo;
    // Sharp: most of the step within 1.5 reference steps of the middle, and plateaus
    // at the probes (eta 1.5 reference steps further out is the same; in the tails of
    // a wider ramp the probes' middle is no face, and the ramp goes on changing).
    float further = abs(e_further_hi - eta_hi) + abs(e_further_lo - eta_lo);
    float ratio = face_step > 0.0 ? across / face_step : 0.0;
    float flatness = face_step > 0.0 ? further / face_step : 1.0;
    float sharp = smoothstep(0.75, 0.85, ratio) * (1.0 - smoothstep(0.05, 0.15, flatness));
    return sharp;
}

// Advance to the next plane, turning on the way (eq. 4.3). v = eta dx/ds.
//
// A face of glass is the volume's picture of a sharp interface: eta steps between two
// plateaus within a voxel or two (a segmented or antialiased surface). There the ray
// turns once, by Snell's law between the plateaus, where it meets the face's middle,
// about the smoothed normal there, and goes on to the next plane in its new
// direction; |v| is the plateau's eta of the side it is on. The face is found along
// the normal through the step's centre: its plateaus probed 2.5 reference steps
// beyond the step either side, its middle by bisection between them, its width from
// eta 1.5 reference steps either side of the middle (a face: most of the step within
// them).
// Turning at the plane after the crossing instead delayed every turn by half a plane
// spacing on average: a ball's exit directions were off by 0.2° at its centre to 4°
// at its rim at sample distance 1 (docs/NOTES.md). The side is judged by |v|, not by
// the eta sampled at this plane, so no crossing is missed between two planes.
//
// A graded change of eta (wider than the face test, or too weak for it) is integrated
// as such, by a Snell step from eta here to eta at the next plane taken at the step's
// middle (the stratified medium's invariant, second order in the step). Weaker still
// (below 0.06 across the probes: noise, thin skins) the thesis' kick, v += ds grad(eta):
// a skin of eta thinner than the probes (the demo floor's: its value ramp crosses the
// glass's eta band) was turned twice by Snell steps about normals from different
// planes, and the floor behind it striped (row to row 1.6 % against 0.7 % with the
// kick); in noise the normal points anywhere and a Snell step at a grazing angle to it
// turns a ray far for a tiny change of eta. Within a film (a skin the classification
// made, see the faces above: eta between the probes' values peaks past both) not even
// the kick: its central differences one voxel apart catch a skin thinner than a voxel
// from some planes only, and the floor under the demo's skin striped (6.6-15 % row to
// row in tests/image_quality.rs); the ray turns as between the plateaus, by the face
// step where they differ, not at all where they are alike.
//
// Moves the viewing ray at vp (view space, on this plane; v = vd, eta there eta_here,
// grad eta there grad_eta, the smoothed surface normal at the box's nearest point n_box)
// to the next plane: vd becomes its new v, the return value its point there.
vec3 advance_viewing_ray(vec3 vp, inout vec3 vd, float eta_here, vec3 grad_eta, vec3 n_box,
                         bool in_box) {
    float ds = P.planes.y;
    float ref_step = P.planes.w;
    if (vd.z < MIN_FORWARD * length(vd)) {
        count_clamp(2u);
        vd = limit_direction(vd);
    }
    vec3 d = normalize(vd);
    vec3 q_straight = vp + d * (ds / d.z);
    float eta_b = eta_of(value_at_tex(to_tex(q_straight)));
    // Outside the volume box eta is constant: nothing there turns a ray. (grad_eta's
    // central differences a voxel wide reach back into the box from just outside it; as
    // a kick they turned rays the face step had already turned at the box's face, once or
    // twice as the planes fell: single-pixel diagonal lines across the water stand-in's
    // tank, seen through its back face.)
    vec3 v_kick = vd + (in_box ? length(q_straight - vp) : 0.0) * grad_eta;
    vec3 v_face = vd;
    vec3 q_face = q_straight;
    float face_step = 0.0;
    bool in_film = false;
    // A ray that left the box with its face's turn still pending (|v| still the eta
    // inside: the face step placed the face a hair beyond the step's end, and the ray
    // stepped out) is turned at its first plane outside, about the normal at the box's
    // edge: outside the box the gradient volume is not read, and nothing else would turn
    // it (it left 8° off Snell's direction, tests/refraction_geometry.rs).
    bool pending = abs(length(vd) - eta_here) > 1e-3 * eta_here;
    vec3 n_face = in_box || pending ? n_box : vec3(0.0);
    if (dot(n_face, n_face) > 1e-12) {
        vec3 nn = normalize(n_face);
        vec3 centre = 0.5 * (vp + q_straight);
        float hs = 0.5 * abs(dot(q_straight - vp, nn)) + 2.5 * ref_step;
        float v_plus = value_at_tex(to_tex(centre + hs * nn));
        float v_minus = value_at_tex(to_tex(centre - hs * nn));
        float e_plus = eta_of(v_plus), e_minus = eta_of(v_minus);
        face_step = abs(e_plus - e_minus);
        in_film = film_between(v_minus, v_plus, e_minus, e_plus).x > 0.0;
        if (e_plus < e_minus) nn = -nn;   // nn points to higher eta
        float eta_lo = min(e_plus, e_minus), eta_hi = max(e_plus, e_minus);
        float eta_mid = 0.5 * (eta_lo + eta_hi);
        // The face step's turn counts only where the step is a face's (w_face > 0 below):
        // elsewhere the bisection and the four probes after it are left out by their
        // loops' trip counts, not by a branch (llvmpipe runs both sides of a branch but
        // leaves a loop once all its lanes are done: 0.8-0.9x the viewing rays' time on
        // the demo scene, where most rays cross no face; the image is the same).
        bool face_used = face_step > FACE_STEP_LO;
        vec3 face;
        float sharp = face_sharpness(centre, nn, hs, eta_lo, eta_hi, eta_mid, face_step,
                                     face_used, face);
        // One Snell step from the ray's eta (|v|) to a target: graded, eta at the next
        // plane, at the step's middle; sharp, the plateau of the side the step ends on,
        // where the ray meets the face (or at the middle if it does not cross it here: a
        // no-op on a plateau). Every turn is a Snell step from the ray's own eta about the
        // local normal, so a ray that mixes the two along a face (tails graded, middle
        // sharp) still leaves it in Snell's direction.
        bool beyond = dot(q_straight - face, nn) >= 0.0;
        float eta_side = beyond ? eta_hi : eta_lo;
        vec3 x_sharp = centre;
        if ((length(vd) >= eta_mid) != beyond) {
            float run = dot(q_straight - vp, nn);
            float t = abs(run) > 1e-9 ? clamp(dot(face - vp, nn) / run, 0.0, 1.0) : 0.0;
            x_sharp = mix(vp, q_straight, t);
        }
        vec3 x = mix(centre, x_sharp, sharp);
        vec3 n = surface_gradient(x);
        v_face = refract_step(vd, mix(eta_b, eta_side, sharp), dot(n, n) > 1e-12 ? n : nn);
        if (v_face.z < MIN_FORWARD * length(v_face)) {
            if (face_used) count_clamp(2u);
            v_face = limit_direction(v_face);
        }
        vec3 d2 = normalize(v_face);
        q_face = x + d2 * ((q_straight.z - x.z) / d2.z);
    }
    float w_face = smoothstep(FACE_STEP_LO, FACE_STEP_HI, face_step);
    vd = mix(in_film ? vd : v_kick, v_face, w_face);
    vec3 q = mix(q_straight, q_face, w_face);
    if (vd.z < MIN_FORWARD * length(vd)) {
        count_clamp(2u);
        vd = limit_direction(vd);
    }
    return q;
}

#endif

#if SWEEP_COMPUTE && PASS == 0
// Where the light reaching pixel `px` of this plane left the previous one: the backward
// step's origin, computed as plane_main computes it for its own pixel (same arithmetic,
// so a neighbour's value is bit for bit what that neighbour's invocation holds).
vec3 light_origin(ivec2 px, uint R, float ds) {
    vec3 p = plane_point((vec2(px) + 0.5) / P.camera.zw, pc.depth);
    vec3 ld = READ_PIXEL(light_direction, R, px).xyz;
    return p - ld * (ds / ld.z);
}
#endif

#if PASS == 0
// Elliptical 3-tap kernel (after Patel et al.; sect. 5.2): a disc of radius `softness`
// reference steps perpendicular to the light (direction ld_here at this pixel), projected
// onto the previous plane around uv_lp (stretched along the light's lateral direction),
// with a per-pixel, per-plane random rotation. Applied at every plane, the blur
// accumulates (incremental convolution): penumbrae widen with distance behind the
// occluder and with softness.
void soft_light_at(vec2 uv_lp, vec3 ld_here, float softness, uint R, out vec3 light_prev,
                   out vec3 dir_prev) {
    float ds = P.planes.y;
    float ref_step = P.planes.w;
    light_prev = vec3(0.0);
    dir_prev = vec3(0.0);
    vec3 dn = normalize(ld_here);
    float radius = softness * ref_step;                          // world units
    vec2 lateral = length(dn.xy) > 1e-6 ? normalize(dn.xy) : vec2(1.0, 0.0);
    vec2 across = vec2(-lateral.y, lateral.x);
    float world_per_uv_y = 2.0 * (pc.depth - ds) * P.camera.x;  // plane i-1 height
    vec2 to_uv = vec2(1.0 / (world_per_uv_y * P.camera.y), -1.0 / world_per_uv_y);
    float rot = 2.0 * PI * hash(uvec3(FRAG_XY, pc.plane));
    for (int k = 0; k < 3; ++k) {
        float phi = rot + float(k) * (2.0 * PI / 3.0);
        vec2 offset = radius * (cos(phi) / dn.z * lateral + sin(phi) * across);
        vec3 l, d;
        light_at(uv_lp + offset * to_uv, R, l, d);
        light_prev += l;
        dir_prev += d;
    }
    light_prev /= 3.0;
    dir_prev /= 3.0;
}

// The backward (semi-Lagrangian) light step of Algorithm 1 (sect. 4.2, 5.2): the light
// reaching this plane's pixel (uv, pixel) from the previous plane, attenuated over the
// step (eq. 4.4) and scaled by the intensity law (eqs. 4.6-4.8), and its direction
// turned by grad eta (eq. 4.5). Called from main's uniform control flow: the fragment
// path's derivatives (dFdxFine) need every lane of the quad.
void backward_light_step(vec2 uv, ivec2 pixel, out vec3 light, out vec3 light_dir) {
    vec2 size = P.camera.zw;
    uint R = pc.read_layer;
    float ds = P.planes.y;
    float ref_step = P.planes.w;
    vec3 p = plane_point(uv, pc.depth);
    vec3 ld_here = READ_PIXEL(light_direction, R, pixel).xyz;
    // Backward (semi-Lagrangian) step: follow the light direction back to plane i-1.
    vec3 lp = p - ld_here * (ds / ld_here.z);
    vec2 uv_lp = project(lp);

    // The light arriving at lp from the previous plane: through the soft kernel where
    // the light is soft (soft_light_at), else one light-weighted bilinear read.
    vec3 light_prev = vec3(0.0);
    vec3 dir_prev = vec3(0.0);
    float softness = P.light_dir.w;
    if (HAVE_SOFT_LIGHT && softness > 0.0) {
        soft_light_at(uv_lp, ld_here, softness, R, light_prev, dir_prev);
    } else {
        light_at(uv_lp, R, light_prev, dir_prev);
    }

    // Intensity law (eqs. 4.6-4.8): I = S_{i-1} / S_i, the areas of this pixel's footprint
    // on this plane and of the light's origin on the previous one. Areas from the cross
    // product of the screen-space derivatives (exact for sheared footprints).
#if SWEEP_COMPUTE
    // The fine derivatives of a fragment quad, as explicit differences with the quad
    // neighbour (the pixel whose x, or y, differs in the lowest bit): right minus left,
    // lower minus upper, the same value for both pixels of a pair, as dFdxFine and
    // dFdyFine give it. Where the neighbour lies past the image's edge (an odd size) the
    // pixel on the other side stands in. p is linear in the pixel, so its differences
    // are the neighbour's p minus this one's.
    ivec2 isize = ivec2(size);
    ivec2 nx = ivec2(pixel.x ^ 1, pixel.y), ny = ivec2(pixel.x, pixel.y ^ 1);
    if (nx.x >= isize.x) nx.x = pixel.x - 1;
    if (ny.y >= isize.y) ny.y = pixel.y - 1;
    float sx = nx.x > pixel.x ? 1.0 : -1.0, sy = ny.y > pixel.y ? 1.0 : -1.0;
    vec3 p_x = plane_point((vec2(nx) + 0.5) / size, pc.depth);
    vec3 p_y = plane_point((vec2(ny) + 0.5) / size, pc.depth);
    float s_here = length(cross(sx * (p_x - p), sy * (p_y - p)));
    float s_prev = length(cross(sx * (light_origin(nx, R, ds) - lp),
                                sy * (light_origin(ny, R, ds) - lp)));
#else
    float s_here = length(cross(dFdxFine(p), dFdyFine(p)));
    float s_prev = length(cross(dFdxFine(lp), dFdyFine(lp)));
#endif
    float gain = s_prev / s_here;
    // Chapter 7's bright spots: neighbours with very different directions give huge
    // footprints. Bound the gain per plane (P.max_gain) and never let NaN/Inf through.
    if (!(gain >= 0.0) || isinf(gain)) gain = 1.0;
    if (gain > P.max_gain) {
        count_clamp(3u);
        gain = P.max_gain;
    }

    float f_p, f_lp;
    vec3 grad_eta_p;
    sample_field_where(p, eta_may_vary_near(p), f_p, grad_eta_p);
    f_lp = value_at_tex(to_tex(lp));
    float light_len = length(p - lp);
    vec3 seg_c; float seg_a; vec3 seg_m;
    segment(f_lp, f_p, light_len / ref_step, clipped(p), seg_c, seg_a, seg_m);
    light = light_prev * gain * (1.0 - seg_a) * seg_m;               // eq. 4.4
    // Not turned by a film the light crosses (see the forward rays above): the plateaus
    // 2.5 reference steps before and beyond the step, along the light.
    vec3 l_unit = normalize(ld_here);
    float v_before = value_at_tex(to_tex(lp - 2.5 * ref_step * l_unit));
    float v_after = value_at_tex(to_tex(p + 2.5 * ref_step * l_unit));
    bool light_in_film =
        film_between(v_before, v_after, eta_of(v_before), eta_of(v_after)).x > 0.0;
    light_dir = dir_prev + (light_in_film ? 0.0 : light_len) * grad_eta_p;   // eq. 4.5
    if (light_dir.z < MIN_FORWARD * length(light_dir)) count_clamp(0u);
    light_dir = limit_direction(light_dir);
    if (any(isnan(light)) || any(isinf(light))) light = vec3(0.0);
}
#endif

#if PASS != 1
// The smoothed surface normal (the gradient volume) at the box's point nearest to vp, and
// whether vp lies in the box. One read: a ray just outside the box may still need its
// face's normal (advance_viewing_ray's face step), though no segment outside has a face.
vec3 normal_at_box(vec3 vp, out bool in_box) {
    vec3 t_here = to_tex(vp);
    in_box = all(greaterThanEqual(t_here, vec3(0.0))) && all(lessThanEqual(t_here, vec3(1.0)));
    return surface_gradient_tex(clamp(t_here, vec3(0.0), vec3(1.0)));
}

// One segment of a viewing ray (sect. 4.3; from its previous point, value v_prev and eta
// eta_prev, to vp on this plane, value f_v and eta eta_here; v = vd, dir its unit
// direction, seg_len long, n_here the smoothed normal at vp) composited into its colour
// C, opacity A and medium M (Oddy-Willis, eq. 4.13): the segment's own colour and
// opacity (viewing_segment) lit by this plane's light (segment_light), the reflection
// and highlight of a face it meets (face_met, face_highlight). Returns the ray's new
// skin chain code (segment_light; 0 unlit), from chain_in, the code it carried.
float composite_segment(vec3 vp, vec3 vd, vec3 dir, float seg_len, float v_prev,
                        float eta_prev, float f_v, float eta_here, vec3 n_here,
                        float chain_in, uint R, inout vec3 C, inout float A, inout vec3 M) {
    float chain_code = 0.0;
    vec2 uv_v = project(vp);
    vec3 c; float a; vec3 m;
    viewing_segment(vp, dir, seg_len, v_prev, f_v, c, a, m);
#if FORWARD_LIGHT
    // The light of this plane's segment (i-1 -> i): the irradiance where the ray
    // enters it, on plane i-1 (the segment's front, as the backward step uses).
    vec2 uv_front = project(vp - dir * seg_len);
    vec3 i_d = READ_BUFFER(irradiance, R, uv_front).rgb;
#else
    vec3 i_d = READ_BUFFER(light_colour, R, uv_v).rgb;
#endif
    // Direction the light travels at the segment's front, where i_d is read: at a
    // face, the side the light meets it from (read at the segment's back, a plane
    // beyond a face, it was the refracted light's direction or not depending on how
    // the planes fell: a highlight banded at the plane spacing).
#if FORWARD_LIGHT
    vec3 ldir = splatted_direction(READ_BUFFER(irradiance_direction, R, uv_front));
#else
    vec3 ldir = normalize(READ_BUFFER(light_direction, R, uv_v).xyz);
#endif
    vec3 i_s = vec3(0.0);
    vec3 c_ambient = vec3(0.0);
    bool unlit = P.unlit != 0u;
    if (unlit) {
        i_d = vec3(1.0);
    } else {
        chain_code = segment_light(dir, ldir, f_v, v_prev, n_here, a, seg_len, chain_in, c,
                                   c_ambient, i_d);
    }
    bool reflections = HAVE_REFLECTIONS && P.refraction.y > 0.5;
    bool specular = HAVE_SPECULAR && P.specular.y > 0.0 && !unlit;
    if (reflections || specular) {
        float reflected, highlight_ratio;
        vec3 reflected_dir, highlight_n;
        face_met(vp, vd, dir, seg_len, n_here, v_prev, eta_prev, f_v, eta_here, reflections,
                 reflected, reflected_dir, highlight_n, highlight_ratio);
        if (reflected > 0.0) {
            C += (1.0 - A) * M * reflected * environment_radiance(reflected_dir);
            A += (1.0 - A) * reflected;
        }
        if (specular && dot(highlight_n, highlight_n) > 0.0) {
            i_s = face_highlight(vp, dir, seg_len, ldir, highlight_n, highlight_ratio, R);
        }
    }
    // Oddy-Willis compositing (eq. 4.13): the medium factor once, specular not
    // multiplied by opacity.
    C += (1.0 - A) * M * (c * i_d + c_ambient * P.ambient.rgb + i_s);
    A += (1.0 - A) * a;
    M *= m;
    return chain_code;
}

#endif

#if PASS == 1
// The forward transport's light-ray pass for one ray texel (`pixel` of the ray images;
// read layer R): its outputs, the ray advanced to this plane.
void light_ray_plane(ivec2 pixel, uint R) {
// ---- light propagation, forward (Lagrangian) --------------------------------------
// Each texel of the light state is one light ray: flux (rgb) and its position on the
// previous plane (.w of both buffers), direction v = eta dx/ds (eq. 4.2). The ray is
// advanced to this plane on its own; no neighbour's direction bends it, so rays cross
// through a focus as they do physically (thesis ch. 7's bright spots came from the
// backward step's one direction per pixel). Irradiance is made from the rays
// afterwards by light_splat.*, which conserves their flux.
// This draw covers the ray images; texels past the grid hold no ray.
int r = pixel.y * int(P.light_rays.z) + pixel.x;
ivec2 ray = ivec2(r % int(P.light_rays.x), r / int(P.light_rays.x));
if (!ray_exists(ray)) {
    out_light_colour = vec4(0.0);
    out_light_direction = vec4(0.0, 0.0, 1.0, 0.0);
    return;
}
vec4 lc = READ_RAY(rays_flux, R, r);
vec4 lv = READ_RAY(rays_direction, R, r);
vec3 flux = lc.rgb;
#if SOFT_LIGHT
flux = diffuse_flux(ray, r, lv, flux);   // softness (sect. 5.2) as diffusion
#endif
// To this plane (eqs. 4.2-4.4, advance_light_ray).
vec3 v_new, p_new;
advance_light_ray(lc, lv, flux, v_new, p_new);
out_light_colour = vec4(flux, p_new.x);
out_light_direction = vec4(v_new, p_new.y);
}
#endif

void PLANE_MAIN() {
    vec2 size = P.camera.zw;
    vec2 uv = FRAG_XY / size;
    uint R = pc.read_layer;
    float ds = P.planes.y;
    float ref_step = P.planes.w;
    ivec2 pixel = ivec2(FRAG_XY);

#if PASS == 1
    light_ray_plane(pixel, R);   // the light rays (sect. 4.2), forward
#elif PASS == 0
    // ---- light propagation (sect. 4.2, 5.2) -------------------------------------------
    vec3 light, light_dir;
    backward_light_step(uv, pixel, light, light_dir);
#endif
#if PASS != 1
    // ---- viewing rays (sect. 4.3, 5.2) ------------------------------------------------
    vec4 vp4 = READ_PIXEL(view_position, R, pixel);
    vec4 vd4 = READ_PIXEL(view_direction, R, pixel);
    vec4 CA = READ_PIXEL(colour_opacity, R, pixel);
    vec4 M4 = READ_PIXEL(medium, R, pixel);
#if PASS == 2
    // A finished viewing ray (issue 31): once its opacity reached termination_alpha at
    // plane k (marked below, medium.w = -(k + 1): the skin chain is of no use to it any
    // more) nothing of the volume changes its pixel, so it stops: its state is copied to
    // the other layer once, at plane k + 1, and from k + 2 on both layers hold it and the
    // plane leaves the pixel alone (the render pass loads the layer; the compute path
    // stores nothing). What still depends on it is the environment seen behind the
    // volume through the remaining 1 - A <= 1 - termination_alpha (the composite's
    // C + (1 - A) M env): looked up in the direction the ray had when it finished, where
    // the planes past it could still have turned it.
    if (M4.w < 0.0) {
        if (float(pc.plane) + M4.w >= 1.0) SKIP_PLANE;
        out_view_position = vp4;
        out_view_direction = vd4;
        out_colour_opacity = CA;
        out_medium = M4;
        return;
    }
#endif
    vec3 vp = vp4.xyz;
    vec3 vd = vd4.xyz;
    // A pixel's first plane in the drawn region: on to this plane (catch_up_to_plane).
    catch_up_to_plane(vp, vd, M4.w);
    vec3 C = CA.rgb;
    float A = CA.a;
    vec3 M = M4.rgb;

    float f_v;
    vec3 grad_eta;
    sample_field_where(vp, eta_may_vary_near(vp), f_v, grad_eta);
    float eta_here = eta_of(f_v);
    vec3 dir = normalize(vd);
    float seg_len = ds / dir.z;   // arc length from plane i-1 to this plane

    float chain_code = M4.w;
    // The surface normal at this plane's point: the face's for the segment ending here
    // (zero outside the box), and the probing direction of the step starting here.
    bool in_box;
    vec3 n_box = normal_at_box(vp, in_box);
    vec3 n_here = in_box ? n_box : vec3(0.0);
    if (A < P.termination_alpha) {
        chain_code = composite_segment(vp, vd, dir, seg_len, vp4.w, vd4.w, f_v, eta_here,
                                       n_here, M4.w, R, C, A, M);
    }
    // Advance to the next plane, turning on the way (eq. 4.3; advance_viewing_ray).
    vec3 vp_next = advance_viewing_ray(vp, vd, eta_here, grad_eta, n_box, in_box);

#if PASS == 0
    out_light_colour = vec4(light, 0.0);
    out_light_direction = vec4(light_dir, 0.0);
#endif
#if PASS == 2
    if (A >= P.termination_alpha) chain_code = -(float(pc.plane) + 1.0);   // finished
#endif
    out_view_position = vec4(vp_next, f_v);
    out_view_direction = vec4(vd, eta_here);
    out_colour_opacity = vec4(C, A);
    out_medium = vec4(M, chain_code);
#endif
}

COMPUTE_ENTRY

// One plane of the refractive plane sweep (thesis ch. 4, Algorithm 1): full-screen draws
// that read the previous plane's state from layer `read_layer` and write this plane's
// into the other layer (the render pass's attachments). Included by sweep.frag
// (FORWARD_LIGHT 0, PASS 0: the thesis' backward light step, light and viewing rays in
// one draw) and by the forward transport's two draws, sweep_light_forward.frag (PASS 1:
// the light rays) and sweep_view_forward.frag (PASS 2: the viewing rays), between which
// light_splat.* deposits the rays' flux on the plane. The compute sweep compiles the same
// file with SWEEP_COMPUTE 1 (sweep_plane_io.glsl: what differs).
//
// By thesis step (chapter 4, Algorithm 1), where the functions are:
// - the light, sweep_light_step.glsl: forward (PASS 1) advance_light_ray, eqs. 4.2-4.4
//   in Snell sub-steps (straight_in_clear_space: one where nothing can turn or dim the
//   ray), softness as diffusion between neighbouring rays (diffuse_flux); backward
//   (PASS 0) backward_light_step, eqs. 4.4-4.8 (soft_light_at: the soft kernel of sect.
//   5.2; light_at, below: the bilinear, light-weighted read of the previous plane);
// - the viewing rays (PASS 0, 2), sweep_viewing.glsl: a ray that enters the drawn region
//   late, catch_up_to_plane; the segment from the previous plane, viewing_segment (the
//   preintegration table, eq. 3.19, and the box's faces), lit by segment_light, the face
//   or film it meets (face_met: Fresnel reflection, eq. 4.12) and its highlight
//   (face_highlight, eqs. 4.9-4.11), composited (composite_segment, eq. 4.13); then
//   advance_viewing_ray to the next plane (eq. 4.3: the face step, the graded Snell
//   step, the thesis' kick);
// - here: the helpers both share, the forward light rays' texel (light_ray_plane), the
//   viewing ray's (viewing_ray_plane: reads its state, runs the steps above, writes it)
//   and PLANE_MAIN, which runs the pass's steps for one pixel.
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
#include "fresnel.glsl"
#if FORWARD_LIGHT
#include "sweep_rays.glsl"
#endif

#include "sweep_plane_io.glsl"

#if PASS == 0
BACKWARD_STATE_OUTPUTS;
#define STORE_OUTPUTS(at) STORE_BACKWARD_STATE(at)
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
        vec3 l = READ_LIGHT_PIXEL(light_colour, 0u, layer, c).rgb;
        vec3 d = READ_LIGHT_PIXEL(light_direction, 1u, layer, c).xyz;
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
const float MATTER_OPACITY = 1e-3;   // a segment this opaque or less starts no chain
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

#include "sweep_light_step.glsl"
#include "sweep_viewing.glsl"

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
    // A ray whose texel row the previous plane did not move (pc.pad: those rows, [lo,
    // end) in 16 bits each; render/refract/ray_rows.rs) still holds the setup's launch
    // state, and has crossed empty space since, on a straight line: it steps from the
    // launch plane to the previous plane in one go, then on as every ray does. (Both
    // paths: the compute path's light pass takes the same rows since 2026-12-08.)
    int moved_lo = int(pc.pad & 0xFFFFu), moved_end = int(pc.pad >> 16);
    if (pixel.y < moved_lo || pixel.y >= moved_end) {
        float dz = pc.depth - P.planes.x;   // launch (plane -1) to plane i - 1
        lc.w += lv.x / lv.z * dz;
        lv.w += lv.y / lv.z * dz;
    }
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

#if PASS != 1
// The viewing ray of this pixel through one plane (sect. 4.3, 5.2): read its state, add
// the segment from the last plane (eq. 4.13), advance it to the next plane (eq. 4.3) and
// write its state.
void viewing_ray_plane(ivec2 pixel, uint R) {
    float ds = P.planes.y;
    // The compact state (sweep_plane_io.glsl): the point's x, y; v and the value at the
    // point; colour and opacity; medium and the skin chain (or a mark).
    vec2 vp_xy = READ_VIEW_XY(R, pixel);
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
    if (M4.w <= -1.0) {
        if (float(pc.plane) + M4.w >= 1.0) SKIP_PLANE;
        WRITE_VIEW_XY(vp_xy);
        out_view_direction = vd4;
        out_colour_opacity = CA;
        out_medium = M4;
        return;
    }
#endif
    // On this plane (every step ends on the next one), unless the setup left it on plane
    // 0: then catch_up_to_plane moves it on (a pixel's first plane in the drawn region).
    vec3 vp = vec3(vp_xy, pc.depth);
    vec3 vd = vd4.xyz;
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
        chain_code = composite_segment(vp, vd, dir, seg_len, vd4.w, f_v, eta_here, n_here,
                                       M4.w, R, C, A, M);
    }
    // Advance to the next plane, turning on the way (eq. 4.3; advance_viewing_ray).
    vec3 turned_back;
    vec3 vp_next = advance_viewing_ray(vp, vd, eta_here, grad_eta, n_box, in_box, turned_back);
    // Totally reflected at a face into a direction the sweep cannot follow (back towards
    // the viewer): what the ray sees from here on is what lies that way, looked up as
    // the Fresnel reflections are (the environment, unoccluded), and the ray ends.
    bool reflections = HAVE_REFLECTIONS && P.refraction.y > 0.5;
    if (reflections && dot(turned_back, turned_back) > 0.0 && A < P.termination_alpha) {
        C += (1.0 - A) * M * environment_radiance(normalize(turned_back));
        A = 1.0;
    }
#if PASS == 2
    if (A >= P.termination_alpha) chain_code = -(float(pc.plane) + 1.0);   // finished
#endif
    WRITE_VIEW_XY(vp_next.xy);
    out_view_direction = vec4(vd, f_v);
    out_colour_opacity = vec4(C, A);
    out_medium = vec4(M, chain_code);
}
#endif

void PLANE_MAIN() {
    vec2 uv = FRAG_XY / P.camera.zw;
    uint R = pc.read_layer;
    ivec2 pixel = ivec2(FRAG_XY);
#if PASS == 1
    light_ray_plane(pixel, R);   // the light rays (sect. 4.2), forward
#else
#if PASS == 0
    // The light through this plane (sect. 4.2, 5.2): the thesis' backward step, or the
    // light volume's (`--light-transport eikonal`).
    vec3 light, light_dir;
    if (LIGHT_FROM_VOLUME) {
        // The eikonal light transport: no light on the planes (the viewing rays read the
        // light volume themselves; its light-colour dumps are refused).
        light = vec3(0.0);
        light_dir = P.light_dir.xyz;
    } else {
        backward_light_step(uv, pixel, light, light_dir);
    }
    out_light_colour = vec4(light, 0.0);
    out_light_direction = vec4(light_dir, 0.0);
#endif
    viewing_ray_plane(pixel, R);   // the viewing rays (sect. 4.3), both transports
#endif
}

COMPUTE_ENTRY

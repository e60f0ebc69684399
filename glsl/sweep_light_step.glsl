// The light's step from one plane of the sweep to the next (thesis sect. 4.2, 5.2), part
// of sweep_plane.glsl (which includes it once, after its shared helpers): the forward
// transport's light rays (PASS 1: advance_light_ray, eqs. 4.2-4.4, in Snell sub-steps;
// diffuse_flux, softness as diffusion between neighbouring rays) and the thesis'
// backward step (PASS 0: backward_light_step, eqs. 4.4-4.8, with soft_light_at, the
// soft kernel of sect. 5.2).

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

#if SWEEP_COMPUTE && PASS == 0
// Where the light reaching pixel `px` of this plane left the previous one: the backward
// step's origin, computed as plane_main computes it for its own pixel (same arithmetic,
// so a neighbour's value is bit for bit what that neighbour's invocation holds).
vec3 light_origin(ivec2 px, uint R, float ds) {
    vec3 p = plane_point((vec2(px) + 0.5) / P.camera.zw, pc.depth);
    vec3 ld = READ_LIGHT_PIXEL(light_direction, 1u, R, px).xyz;
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
    vec3 ld_here = READ_LIGHT_PIXEL(light_direction, 1u, R, pixel).xyz;
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

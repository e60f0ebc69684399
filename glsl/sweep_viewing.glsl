// The viewing rays' step from one plane of the sweep to the next (thesis sect. 4.3, eqs.
// 4.3 and 4.9-4.13), part of sweep_plane.glsl (which includes it once, after its shared
// helpers and the light's step): catch_up_to_plane, viewing_segment, segment_light,
// face_met (film_reflection, face_reflection), face_highlight, composite_segment (eq.
// 4.13), and advance_viewing_ray (eq. 4.3; face_sharpness) to the next plane.

#if PASS != 1
// Where the light that reaches the point q crossed the plane dz before q's, in that
// plane's pixels: along the light's direction as it leaves the light (P.light_dir; sweep
// space, z across the planes; bounded as the sweep bounds its directions, MIN_FORWARD),
// not the local one read from the planes. Near a caustic the local direction is the
// flux-weighted mean of crossing rays, noisy from pixel to pixel and with the light's
// slightest turn: read along it, the sphere on its floor changed by 10.8 % (mean
// |difference| / mean) for a light turned by 0.1 degrees, where the read at the ray's own
// point changed by 2.4 % and this one by 2.5 %. Without refraction the two
// are the same; under refraction this one is off by the spacing times the difference of
// the tangents of the local and the launched direction, the old read by that of the
// local direction and the view's.
vec2 light_line_uv(vec3 q, float dz) {
    vec3 l = normalize(P.light_dir.xyz);
    return project(q - l * (dz / max(l.z, MIN_FORWARD)));
}

// A pixel's first plane in the drawn region (render::refract::region): its ray is
// still where the setup put it, on plane 0, and has crossed empty space since (the
// region bounds the box up to beyond this plane). Straight on to this plane, as the
// full-screen sweep would have moved it; the value behind it stays the empty space's.
// Its skin chain (below) starts as the full-screen sweep's would have, at the light
// before any matter: the light of the previous plane where the ray is now.
//
// A ray the setup left there carries the mark VIEW_RAY_AT_SETUP in `chain` (its stored
// point is x, y only: sweep_plane_io.glsl); every other ray is on this plane already.
// Moves vp (the ray's point, direction vd) on to this plane where it is a plane or more
// behind, clears the mark and starts its skin chain there.
void catch_up_to_plane(inout vec3 vp, vec3 vd, inout float chain) {
    uint R = pc.read_layer;
    float ds = P.planes.y;
    if (chain != VIEW_RAY_AT_SETUP) return;
    chain = 0.0;
    vp.z = P.planes.x;   // plane 0, where the setup put it
    if (vp.z < pc.depth - 0.5 * ds) {   // a whole plane or more behind
        // Plane by plane, as the full-screen sweep steps it (the same arithmetic, so the
        // same rounding: in a noisy medium a ray that lands a rounding error elsewhere
        // may take another turn).
        vec3 d0 = normalize(vd);
        for (int k = 0; k < int(P.planes.z) && vp.z < pc.depth - 0.5 * ds; ++k) {
            vp = vp + d0 * (ds / d0.z);
        }
        // The light the full-screen sweep's chain would carry into the segment ending
        // here (chain_start_uv): along the light through the segment's middle, on the
        // previous plane (the full-screen sweep read it a plane earlier on the same line).
        vec2 uv_l = light_line_uv(vp - d0 * (0.5 * ds / d0.z), 0.5 * ds);
#if FORWARD_LIGHT
        vec3 l0 = READ_BUFFER(irradiance, R, uv_l).rgb;
#else
        vec3 l0 = READ_BUFFER(light_colour, R, uv_l).rgb;
#endif
        // (The light volume's light needs no chain: composite_segment.)
        if (P.unlit == 0u && !LIGHT_FROM_VOLUME)
            chain = chain_encode(dot(l0, vec3(0.2126, 0.7152, 0.0722)), 0.0);
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

// Where a segment without matter reads its light: the light the skin chain
// (segment_light) carries into matter that begins in the next segment. The point on
// this segment's front plane (i - 1) from which the light (light_line_uv) reaches the
// next segment's middle, a plane and a half on; in that plane's pixels. The segment runs from vp - dir * seg_len on plane i - 1 to vp on plane
// i. (It emits next to nothing itself, whatever light it reads.)
//
// Read at the viewing ray's own point on plane i - 1 (or at vp's pixel), the chain's
// light was that of a point displaced from the line the light comes along by the
// spacing times the tangent of the angle between light and view: a sphere's shadow on
// its floor lagged by up to a plane along the light, and the sphere's terminator was
// lit too far round (docs/NOTES.md, "The sweep's light, read where it comes from").
// Segments with matter read at their front, as before: there the plane's own light is
// what the layer weight (segment_light) is measured against; read upstream along the
// light, the lit floor under an oblique light came out 1.4 % brighter than the
// analytic c mu_l / (mu_l + mu_v) (sample distance 1; 1.0 % at 0.5), where the front
// gives it to 0.1 %.
vec2 chain_start_uv(vec3 vp, vec3 dir, float seg_len) {
    vec3 next_middle = vp + dir * (0.5 * seg_len);   // 1.5 plane spacings past plane i - 1
    return light_line_uv(next_middle, 1.5 * P.planes.y);
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
    // (The light volume's light, read in the segment's middle where it is not layered,
    // has crossed the segment's matter already: composite_segment.)
    float r = LIGHT_FROM_VOLUME ? 0.0 : dir.z / max(ldir.z, 1e-3);
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
    bool matter = a > MATTER_OPACITY;
    bool have_chain = chain_decode(chain_prev, chained_light, chained_depth);
    if (!LIGHT_FROM_VOLUME && matter && have_chain && layered && chained_depth < CHAIN_DEPTH) {
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
        // nothing is looked up (where the sweep cannot follow it back, PLANE_MAIN looks
        // up what it sees then). (Looking the environment up with F = 1 there and
        // ending the ray was tried: no visible difference on the wine glass; it is done
        // only where the sweep cannot follow the turned ray, advance_viewing_ray.)
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
    // A film: where the value ramps between two matters through a band of eta that
    // belongs to neither (the demo floor's edge passes through the glass's band), eta
    // rises (or falls) and returns between the probes: a skin the classification made,
    // thinner than a face as the sweep knows faces (by their plateaus either side). It
    // reflects as one face between the probes' plateaus (nothing where both are alike),
    // in the one segment whose values pass the film's peak, found in value space (layer 2
    // of the preintegration table): the same whatever the planes. Why not from the plane
    // samples, nor as two faces: docs/NOTES.md, "Known, measured: the demo floor".
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
    vec3 i_face, l_face;
    if (LIGHT_FROM_VOLUME) {
        volume_light(front + off, i_face, l_face);
    } else {
        i_face = READ_BUFFER(light_colour, R, uv_face).rgb;
        l_face = normalize(READ_BUFFER(light_direction, R, uv_face).xyz);
    }
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

// The face step's turn (advance_viewing_ray, below, says why): the face is found along n_face through the step's
// centre, and the ray turns once there; returns where it meets the next plane, with its
// new direction in v_face, the step of eta across the probes in face_step, whether a film
// lies between them in in_film, and turned_back set where the turn leads back towards the
// viewer.
vec3 face_step_turn(vec3 vp, vec3 vd, vec3 q_straight, float eta_b, vec3 n_face,
                    out vec3 v_face, out float face_step, out bool in_film,
                    inout vec3 turned_back) {
    vec3 nn = normalize(n_face);
    vec3 centre = 0.5 * (vp + q_straight);
    float hs = 0.5 * abs(dot(q_straight - vp, nn)) + 2.5 * P.planes.w;
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
    // leaves a loop once all its lanes are done; docs/NOTES.md, "Work only where a
    // face is"). The image is the same.
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
    vec3 n_turn = dot(n, n) > 1e-12 ? n : nn;
    v_face = refract_step(vd, mix(eta_b, eta_side, sharp), n_turn);
    if (v_face.z < MIN_FORWARD * length(v_face)) {
        if (face_used) count_clamp(2u);
        // Turned by a face (totally reflected back towards the viewer, at once at a
        // sharp face, over a few planes through a graded one) into a direction the
        // front-to-back sweep cannot follow. Clamped, the ray went on sideways and out
        // through the face it should not pass (a glass wedge's exit face met at 42-45
        // degrees showed what lies beyond it); the caller ends it with what lies that
        // way instead.
        turned_back = face_step >= FACE_STEP_HI ? v_face : vec3(0.0);
        v_face = limit_direction(v_face);
    }
    vec3 d2 = normalize(v_face);
    return x + d2 * ((q_straight.z - x.z) / d2.z);
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
// The side is judged by |v|, not by the eta sampled at this plane, so no crossing is
// missed between two planes.
//
// A graded change of eta (wider than the face test, or too weak for it) is integrated
// as such, by a Snell step from eta here to eta at the next plane taken at the step's
// middle (the stratified medium's invariant, second order in the step). Weaker still
// (below FACE_STEP_LO across the probes: noise, thin skins) the thesis' kick, v += ds
// grad(eta): a Snell step about a normal that noise points anywhere, or that skins
// thinner than the probes take from different planes, turns rays far for a tiny change
// of eta. Within a film (see face_met) not even the kick: the ray turns as between the
// plateaus, by the face step where they differ, not at all where they are alike. What
// the other choices measured (a turn at the plane after the crossing, Snell steps in
// skins and noise, the kick in films): docs/NOTES.md, "Viewing rays through glass: a
// face is a sharp interface" and "The same day, the films' turns".
//
// Moves the viewing ray at vp (view space, on this plane; v = vd, eta there eta_here,
// grad eta there grad_eta, the smoothed surface normal at the box's nearest point n_box)
// to the next plane: vd becomes its new v, the return value its point there.
vec3 advance_viewing_ray(vec3 vp, inout vec3 vd, float eta_here, vec3 grad_eta, vec3 n_box,
                         bool in_box, out vec3 turned_back) {
    float ds = P.planes.y;
    turned_back = vec3(0.0);
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
        q_face = face_step_turn(vp, vd, q_straight, eta_b, n_face, v_face, face_step, in_film,
                                turned_back);
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

#if PASS != 1
// The smoothed surface normal (the gradient volume) at the box's point nearest to vp, and
// whether vp lies in the box. One read: a ray just outside the box may still need its
// face's normal (advance_viewing_ray's face step), though no segment outside has a face.
vec3 normal_at_box(vec3 vp, out bool in_box) {
    vec3 t_here = to_tex(vp);
    in_box = all(greaterThanEqual(t_here, vec3(0.0))) && all(lessThanEqual(t_here, vec3(1.0)));
    return surface_gradient_tex(clamp(t_here, vec3(0.0), vec3(1.0)));
}

// One segment of a viewing ray (sect. 4.3; from its previous point, value v_prev, to vp
// on this plane, value f_v and eta eta_here; v = vd, dir its unit
// direction, seg_len long, n_here the smoothed normal at vp) composited into its colour
// C, opacity A and medium M (Oddy-Willis, eq. 4.13): the segment's own colour and
// opacity (viewing_segment) lit by this plane's light (segment_light), the reflection
// and highlight of a face it meets (face_met, face_highlight). Returns the ray's new
// skin chain code (segment_light; 0 unlit), from chain_in, the code it carried.
float composite_segment(vec3 vp, vec3 vd, vec3 dir, float seg_len, float v_prev,
                        float f_v, float eta_here, vec3 n_here,
                        float chain_in, uint R, inout vec3 C, inout float A, inout vec3 M) {
    float chain_code = 0.0;
    vec2 uv_v = project(vp);
    vec3 c; float a; vec3 m;
    viewing_segment(vp, dir, seg_len, v_prev, f_v, c, a, m);
#if FORWARD_LIGHT
    // The light of this plane's segment (i-1 -> i): the irradiance where the ray
    // enters it, on plane i-1 (the segment's front, as the backward step uses); without
    // matter, the light its skin chain starts from (chain_start_uv). Its direction, read
    // at the front: at a face, the side the light meets it from (read a plane beyond a
    // face, it was the refracted light's direction or not depending on how the planes
    // fell: a highlight banded at the plane spacing).
    vec2 uv_front = project(vp - dir * seg_len);
    vec3 ldir = splatted_direction(READ_BUFFER(irradiance_direction, R, uv_front));
    vec2 uv_light = a > MATTER_OPACITY ? uv_front : chain_start_uv(vp, dir, seg_len);
    vec3 i_d = READ_BUFFER(irradiance, R, uv_light).rgb;
#else
    vec3 i_d, ldir;
    if (LIGHT_FROM_VOLUME) {
        // The eikonal light transport: the light volume's light, which has crossed
        // whatever lies between the light and the point, from any direction, read in
        // the segment's middle. In homogeneous matter (light from any side) it is used
        // as it is. Where the segment crosses layers of matter (a surface), the light
        // that meets the layer is read upstream of the middle, along the light and out
        // of the layer's voxels (1.5 voxels across the layer), and dimmed within it by
        // segment_light's layer weight (the light's optical depth to a point is
        // |n.v| / |n.l| times the viewing ray's). Read at the middle itself, a
        // surface's light depended on where the planes cut it (the volume's light falls
        // within the surface's voxel): bands at the plane spacing, measured as contour
        // rings on a white sphere and stripes on a floor. Upstream along the light, not
        // along the normal, so a shadow's edge stays where it falls; from the middle,
        // not the front, which lies half a segment towards the eye on average (the
        // shadow of a sphere on a floor moved 0.25 voxels, measured). No skin chain: the
        // volume's light is not resolved at the pixels.
        bool layers = abs(f_v - v_prev) > 1e-4 && dot(n_here, n_here) > 1e-12;
        vec3 middle = vp - dir * (0.5 * seg_len);
        volume_light(middle, i_d, ldir);
        if (layers) {
            float across = abs(dot(normalize(n_here), ldir));
            float upstream = min(1.5 / max(across, 0.375), 4.0) * P.planes.w;
            vec3 unused;
            volume_light(middle - ldir * upstream, i_d, unused);
        }
    } else {
        // The plane's light in this pixel; without matter, as the forward transport's.
        ldir = normalize(READ_BUFFER(light_direction, R, uv_v).xyz);
        vec2 uv_light = a > MATTER_OPACITY ? uv_v : chain_start_uv(vp, dir, seg_len);
        i_d = READ_BUFFER(light_colour, R, uv_light).rgb;
    }
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
        // (eta at the previous point is not kept in the state: sweep_plane_io.glsl.)
        face_met(vp, vd, dir, seg_len, n_here, v_prev, eta_of(v_prev), f_v, eta_here, reflections,
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

// One light ray's deposit on its plane, shared by the three ways to splat it: point
// sprites with additive blending (light_splat_sprite.glsl, the fragment path's `splat=raster`),
// a compute shader adding fixed-point values with integer atomics (light_splat.comp,
// `splat=compute`) and the compute sweep's tile-binned gather (sweep_deposit.comp,
// sweep_gather.comp). Two deposits, the `deposit` lever (specialization constant 9):
//
// Cells (the default, issue 32). Neighbouring light rays span the wavefront: ray (i, j)
// owns the cell whose corners are rays (i, j), (i+1, j), (i+1, j+1), (i, j+1), cut along
// its diagonal into two triangles. Each triangle carries the flux its corners' rays
// share with it (a ray is a corner of six triangles: a sixth of each corner's flux,
// conserving the total exactly away from the grid's edge, which lies two cells outside
// every plane's view) and spreads it over the area it spans on this plane with a density
// linear between its corners (triangle_weights: exact integrals over each pixel's part of
// the triangle). So irradiance = flux / area is the intensity law (eqs. 4.6-4.8) by
// construction: evenly lit planes are uniform whatever the rays' spacing against the
// pixels, smooth media give smooth light, light dimmed along the way varies smoothly
// across a cell (a uniform density per triangle striped floors lit at grazing angles,
// where the light's edge crosses cells: 5 % row to row, measured), cells that converge
// concentrate their flux, and a cell folded by a crossing (a caustic) deposits over its
// absolute area. A triangle much smaller than a pixel deposits all its flux into the
// pixels it covers. Torn cells (see cell_of_ray) fall back to boxes.
//
// Boxes (the deposit before issue 32). Each ray deposits its flux over a box the size of
// its cell centred on itself; the boxes do not tile a distorted wavefront (a lattice on
// lit floors where the rays are sparser than the pixels, caustics with the grid's
// shape).
#ifndef REFRAKT_LIGHT_SPLAT_RAY_GLSL
#define REFRAKT_LIGHT_SPLAT_RAY_GLSL
#include "triangle_coverage.glsl"

#ifdef DEPOSIT_BOXES_ONLY
// A shader built for the boxes deposit alone (light_splat_boxes.*: fewer varyings); the
// pipeline's constant 9 is then not in the module and changes nothing.
const bool DEPOSIT_CELLS = false;
#else
layout(constant_id = 9) const bool DEPOSIT_CELLS = true;
#endif

// What a light ray deposits per unit area (constant 11; `SweepOptions::plane_flux` sets it
// off). On (the default): the fluence, the ray's flux per unit area *across the ray*,
// which is what matter scatters (the in-scattered radiance is sigma_s p(theta) times the
// fluence of each beam, summed over the beams that cross there). The intensity law
// spreads a ray's flux over the area its cell spans on the plane, A_plane = A_perp /
// cos(theta), theta the ray's angle to the sweep axis; the plane's light is normalised
// so that the light as launched (theta_0) reads its colour. So each ray's share is
// scaled by cos(theta_0) / cos(theta) (fluence_weight): 1 for light going as launched,
// more for light turned towards the planes. Per ray, before the deposits add: where
// rays cross at different angles no per-pixel direction could undo it afterwards (the
// pixel's mean direction recovered a quarter of the difference in the oblique shadow
// of the sphere on its floor; docs/NOTES.md, "The light the matter scatters"). Off: the
// flux per unit plane area, the thesis' intensity law, which power through a plane is
// the sum of (the power tests) and a photon tracer's plane tally measures. Rays turned
// beyond 84 degrees are dropped (sweep_plane.glsl), so cos(theta) >= 0.104 and the weight
// stays below 10.
layout(constant_id = 11) const bool LIGHT_FLUENCE = true;

float fluence_weight(vec3 v) {
    if (!LIGHT_FLUENCE) return 1.0;
    float speed = length(v);
    // A dropped ray (v = 0) deposits nothing anyway; keep its weight finite.
    if (!(speed > 0.0)) return 1.0;
    return abs(P.light_dir.z) / max(abs(v.z) / speed, 0.1);
}

struct RayDeposit {
    // Cells: the corners' fluxes (rgb, a = luminance) per pixel's world area, halved:
    // each triangle's density is linear between its corners, f_v / (2 area) at corner v
    // (triangle_weights). Zero when the cell is torn (below) or there is none.
    vec4 flux_a;
    vec4 flux_b;
    vec4 flux_c;
    vec4 flux_d;
    // The box: irradiance per pixel² of overlap (rgb, a = luminance), and where it lies
    // (lo.xy, hi.xy, pixels). Boxes: the ray's whole flux. Cells: the ray's shares of the
    // torn cells it is a corner of (zero when none is).
    vec4 box_amplitude;
    vec4 box;
    // Where the whole deposit lies, pixels: lo.xy, hi.xy.
    vec4 footprint;
    // Cells: corners A, B and C, D in pixels.
    vec4 corners_ab;
    vec4 corners_cd;
    vec3 direction;   // unit light direction
};

vec2 ray_position(ivec2 c, uint layer) {
    int r = ray_index(c);
    return vec2(READ_RAY(rays_flux, layer, r).w, READ_RAY(rays_direction, layer, r).w);
}

// View-space units to pixels on the plane at `depth` (magnitudes).
vec2 pixels_per_unit(float depth) {
    float half_h = depth * P.camera.x;
    return vec2(P.camera.z / (2.0 * half_h * P.camera.y), P.camera.w / (2.0 * half_h));
}

vec4 with_luminance(vec3 a) { return vec4(a, dot(a, vec3(0.2126, 0.7152, 0.0722))); }

void clear_deposit(out RayDeposit d) {
    d.flux_a = vec4(0.0);
    d.flux_b = vec4(0.0);
    d.flux_c = vec4(0.0);
    d.flux_d = vec4(0.0);
    d.box_amplitude = vec4(0.0);
    d.box = vec4(0.0);
    d.footprint = vec4(0.0);
    d.corners_ab = vec4(0.0);
    d.corners_cd = vec4(0.0);
    d.direction = vec3(0.0);
}

// A ray's box: centred on it (`centre`, pixels), its widths the sums of the shorter
// one-sided differences to its neighbours along each grid axis (ei, ej: across a
// discontinuity, a silhouette or a shadow's edge, the smooth side gives the cell size),
// each at most 2 * transport.w pixels (wider boxes keep all their flux, over that box),
// carrying `flux`.
void ray_box(vec3 flux, vec2 centre, vec2 ei, vec2 ej, float pixel_area, inout RayDeposit d) {
    vec2 w = clamp(abs(ei) + abs(ej), vec2(1e-3), vec2(2.0 * P.transport.w));
    d.box_amplitude = with_luminance(flux / (w.x * w.y * pixel_area));
    d.box = vec4(centre - 0.5 * w, centre + 0.5 * w);
}

vec2 shorter(vec2 a, vec2 b) { return dot(a, a) <= dot(b, b) ? a : b; }

// The 3 x 3 rays around ray (i, j) (k = (dy + 1) * 3 + dx + 1; the ray itself is k = 4):
// position on this plane (pixels), flux, whether it exists and was not dropped (a
// dropped ray has direction zero and a stale position, sweep_plane.glsl).
struct Neighbourhood {
    vec2 at[9];
    vec3 flux[9];
    bool exists[9];
    bool live[9];
    vec3 direction;   // ray (i, j)'s
};

Neighbourhood neighbourhood(ivec2 c, uint layer, float depth) {
    Neighbourhood n;
    n.direction = vec3(0.0);
    for (int k = 0; k < 9; ++k) {
        ivec2 q = c + ivec2(k % 3 - 1, k / 3 - 1);
        n.exists[k] = ray_exists(q);
        int r = n.exists[k] ? ray_index(q) : 0;
        vec4 lc = READ_RAY(rays_flux, layer, r);
        vec4 lv = READ_RAY(rays_direction, layer, r);
        n.at[k] = project(vec3(lc.w, lv.w, depth)) * P.camera.zw;
        n.flux[k] = n.exists[k] ? lc.rgb * fluence_weight(lv.xyz) : vec3(0.0);
        n.live[k] = n.exists[k] && dot(lv.xyz, lv.xyz) > 0.0;
        if (k == 4) n.direction = lv.xyz;
    }
    return n;
}

// Whether the cell of corners a, b, c, e (indices into n) exists, and whether it is torn:
// a corner dropped, or the corners more than 2 * transport.w pixels apart (rays either
// side of a silhouette: a wavefront torn apart, where interpolating between the corners
// smears light across a shadow).
bvec2 cell_state(Neighbourhood n, int a, int b, int c, int e) {
    bool exists = n.exists[a] && n.exists[b] && n.exists[c] && n.exists[e];
    vec2 lo = min(min(n.at[a], n.at[b]), min(n.at[c], n.at[e]));
    vec2 hi = max(max(n.at[a], n.at[b]), max(n.at[c], n.at[e]));
    bool torn = !(n.live[a] && n.live[b] && n.live[c] && n.live[e])
                || any(greaterThan(hi - lo, vec2(2.0 * P.transport.w)));
    return bvec2(exists, torn);
}

// The boxes deposit: ray `index`'s flux over its box.
bool box_of_ray(int index, uint layer, float depth, out RayDeposit d) {
    ivec2 c = ivec2(index % int(P.light_rays.x), index / int(P.light_rays.x));
    clear_deposit(d);
    vec4 lc = READ_RAY(rays_flux, layer, index);
    vec4 lv = READ_RAY(rays_direction, layer, index);
    if (!(max(lc.r, max(lc.g, lc.b)) > 0.0)) return false;
    vec2 here = vec2(lc.w, lv.w);
    vec2 px_per_unit = pixels_per_unit(depth);
    vec2 big = vec2(1e30);
    vec2 e[4];
    for (int k = 0; k < 4; ++k) {
        ivec2 axis = k < 2 ? ivec2(1, 0) : ivec2(0, 1);
        ivec2 q = c + (k % 2 == 0 ? axis : -axis);
        // A dropped neighbour (direction zero, position stale) counts as missing: its
        // stale position widened boxes across a totally reflecting face (0.6 % of the
        // light beyond a wedge's face at 47°, measured, where none passes).
        bool live = ray_exists(q)
                    && dot(READ_RAY(rays_direction, layer, ray_index(q)).xyz,
                           READ_RAY(rays_direction, layer, ray_index(q)).xyz) > 0.0;
        vec2 p = live ? ray_position(q, layer) : here + (k % 2 == 0 ? big : -big);
        e[k] = (k % 2 == 0 ? p - here : here - p) * px_per_unit;
    }
    vec2 centre = project(vec3(here, depth)) * P.camera.zw;
    ray_box(lc.rgb * fluence_weight(lv.xyz), centre, shorter(e[0], e[1]), shorter(e[2], e[3]),
            1.0 / (px_per_unit.x * px_per_unit.y), d);
    d.footprint = d.box;   // the gather's packed deposit and the boxes' sprite rely on it
    d.direction = normalize(lv.xyz);
    return true;
}

// The cells deposit of ray (i, j): the two triangles of the cell it owns (corners A = (i,
// j), B = (i+1, j), C = (i+1, j+1), D = (i, j+1)) unless that cell is torn, and, over its
// box (as the boxes deposit draws it), its shares of the torn cells it is a corner of: a
// corner's share of a cell is what the cell's triangles take of its flux (A and C: a
// third, in both triangles; B and D: a sixth). The box reaches half way to the
// neighbours on the sides where the torn cells lie. So a torn cell's flux stays where its
// rays went, each corner's part beside that corner, and a region of torn cells deposits
// as the boxes did. Tried first: a torn cell's whole flux in one box at its
// corners' centre (where no ray went, between rays that passed a sphere and rays it
// bent: specks of +45 % on an evenly lit floor), as wide as its corners spread (a halo of
// up to +14 % beside the shadow) and as ray A's box (a rim of up to +30 % at the
// shadow's edge), measured; the corners' shares in whole boxes centred on them still
// left a rim (half of each box lies over intact cells).
bool cell_of_ray(int index, uint layer, float depth, out RayDeposit d) {
    ivec2 c = ivec2(index % int(P.light_rays.x), index / int(P.light_rays.x));
    clear_deposit(d);
    Neighbourhood n = neighbourhood(c, layer, depth);
    vec2 px_per_unit = pixels_per_unit(depth);
    float pixel_area = 1.0 / (px_per_unit.x * px_per_unit.y);
    // The four cells ray (i, j) is a corner of, and its share of each.
    bvec2 own = cell_state(n, 4, 5, 8, 7);    // A
    bvec2 left = cell_state(n, 3, 4, 7, 6);   // B of the cell at (i-1, j)
    bvec2 both = cell_state(n, 0, 1, 4, 3);   // C of the cell at (i-1, j-1)
    bvec2 up = cell_state(n, 1, 2, 5, 4);     // D of the cell at (i, j-1)
    float share = (all(own) ? 1.0 / 3.0 : 0.0) + (all(left) ? 1.0 / 6.0 : 0.0)
                  + (all(both) ? 1.0 / 3.0 : 0.0) + (all(up) ? 1.0 / 6.0 : 0.0);
    vec3 box_flux = n.live[4] ? share * n.flux[4] : vec3(0.0);
    bool triangles = own.x && !own.y;
    vec3 f1 = triangles ? (n.flux[4] + n.flux[5] + n.flux[8]) / 6.0 : vec3(0.0);
    vec3 f2 = triangles ? (n.flux[4] + n.flux[8] + n.flux[7]) / 6.0 : vec3(0.0);
    bool has_box = max(box_flux.r, max(box_flux.g, box_flux.b)) > 0.0;
    bool has_cell = max(max(max(f1.r, f1.g), f1.b), max(max(f2.r, f2.g), f2.b)) > 0.0;
    if (!has_box && !has_cell) return false;
    d.direction = dot(n.direction, n.direction) > 0.0 ? normalize(n.direction) : vec3(0.0, 0.0, 1.0);
    vec2 big = vec2(1e30);
    vec2 ei = shorter(n.live[5] ? n.at[5] - n.at[4] : big, n.live[3] ? n.at[4] - n.at[3] : big);
    vec2 ej = shorter(n.live[7] ? n.at[7] - n.at[4] : big, n.live[1] ? n.at[4] - n.at[1] : big);
    // The box covers only the sides of the ray whose cells are torn (the cells on the
    // other sides deposit their triangles up to the ray): along the grid's i axis the
    // cells own and up lie on its + side, left and both on its - side; along j own and
    // left on the + side, both and up on the - side.
    bool torn_own = all(own), torn_left = all(left), torn_both = all(both), torn_up = all(up);
    vec2 a = vec2(torn_left || torn_both ? -0.5 : 0.0, torn_own || torn_up ? 0.5 : 0.0);
    vec2 b = vec2(torn_both || torn_up ? -0.5 : 0.0, torn_own || torn_left ? 0.5 : 0.0);
    ei = clamp(ei, vec2(-P.transport.w), vec2(P.transport.w));
    ej = clamp(ej, vec2(-P.transport.w), vec2(P.transport.w));
    vec2 q0 = n.at[4] + a.x * ei + b.x * ej, q1 = n.at[4] + a.y * ei + b.x * ej;
    vec2 q2 = n.at[4] + a.x * ei + b.y * ej, q3 = n.at[4] + a.y * ei + b.y * ej;
    d.box = vec4(min(min(q0, q1), min(q2, q3)), max(max(q0, q1), max(q2, q3)));
    vec2 w = max(d.box.zw - d.box.xy, vec2(1e-3));
    d.box.zw = d.box.xy + w;
    d.box_amplitude = has_box ? with_luminance(box_flux / (w.x * w.y * pixel_area)) : vec4(0.0);
    float half_density = triangles ? 0.5 / pixel_area : 0.0;
    d.flux_a = with_luminance(n.flux[4] * half_density);
    d.flux_b = with_luminance(n.flux[5] * half_density);
    d.flux_c = with_luminance(n.flux[8] * half_density);
    d.flux_d = with_luminance(n.flux[7] * half_density);
    d.corners_ab = vec4(n.at[4], n.at[5]);
    d.corners_cd = vec4(n.at[8], n.at[7]);
    vec2 lo = min(min(n.at[4], n.at[5]), min(n.at[8], n.at[7]));
    vec2 hi = max(max(n.at[4], n.at[5]), max(n.at[8], n.at[7]));
    vec4 cell = vec4(lo, hi);
    d.footprint = !has_box ? cell
                : !has_cell ? d.box
                : vec4(min(cell.xy, d.box.xy), max(cell.zw, d.box.zw));
    return true;
}

// The deposit of the light ray `index` (read from `layer`) on the plane at `depth`; false
// when it deposits nothing.
bool ray_deposit(int index, uint layer, float depth, out RayDeposit d) {
    if (DEPOSIT_CELLS) return cell_of_ray(index, layer, depth, d);
    return box_of_ray(index, layer, depth, d);
}

// The area (pixels²) of the box `footprint` (lo.xy, hi.xy) that pixel `p` (integer
// corner) covers.
float deposit_overlap(vec4 footprint, vec2 p) {
    vec2 lo = max(footprint.xy, p);
    vec2 hi = min(footprint.zw, p + 1.0);
    vec2 overlap = max(hi - lo, vec2(0.0));
    return overlap.x * overlap.y;
}

// The irradiance (rgb) and luminance-weighted direction (xyz, w = the weight) pixel `p`
// (integer corner) receives from deposit `d`, divided by `unit`.
void deposit_at(RayDeposit d, vec2 p, float unit, out vec3 e, out vec4 dir) {
    vec4 a = d.box_amplitude * deposit_overlap(d.box, p);
    if (DEPOSIT_CELLS) {
        vec2 ca = d.corners_ab.xy, cb = d.corners_ab.zw, cc = d.corners_cd.xy;
        vec2 cd = d.corners_cd.zw;
        vec3 t1 = triangle_weights(ca, cb, cc, p);
        vec3 t2 = triangle_weights(ca, cc, cd, p);
        a += d.flux_a * (t1.x + t2.x) + d.flux_b * t1.y + d.flux_c * (t1.z + t2.y)
             + d.flux_d * t2.z;
    }
    a /= unit;
    e = a.rgb;
    dir = vec4(d.direction * a.a, a.a);
}

#endif

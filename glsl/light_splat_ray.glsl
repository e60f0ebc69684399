// One light ray's deposit on its plane, shared by the two ways to splat it (the `splat`
// lever): point sprites with additive blending (light_splat.vert/.frag) and a compute
// shader that adds fixed-point values with integer atomics (light_splat.comp).
//
// The deposit is the ray's cell on this plane (the extent of the parallelogram spanned
// by its neighbouring rays), a box the ray's flux is spread over uniformly; each pixel
// receives the flux of the part of the box it covers (exact area overlap). So each ray
// deposits exactly its flux (power is conserved by construction, up to rays that land
// outside the viewport), evenly spaced rays tile the plane and give an exactly uniform
// field whatever their spacing against the pixels (a tent sampled at the pixel centres
// and normalised per ray rippled by ±10 %, measured), converging rays concentrate their
// flux (a caustic) and crossing rays simply overlap.
#ifndef REFRAKT_LIGHT_SPLAT_RAY_GLSL
#define REFRAKT_LIGHT_SPLAT_RAY_GLSL

struct RayDeposit {
    vec4 amplitude;   // rgb = irradiance per pixel² of overlap, a = luminance
    vec4 footprint;   // xy = centre (pixels), zw = box widths (pixels)
    vec3 direction;   // unit light direction
};

vec2 ray_position(ivec2 c, uint layer) {
    int r = ray_index(c);
    return vec2(READ_RAY(rays_flux, layer, r).w, READ_RAY(rays_direction, layer, r).w);
}

// The shorter of the two one-sided differences to the neighbours along `axis`: across a
// discontinuity (a silhouette, a shadow edge) the smooth side gives the cell size.
vec2 cell_edge(ivec2 c, vec2 here, ivec2 axis, uint layer) {
    ivec2 a = c + axis, b = c - axis;
    vec2 da = ray_exists(a) ? ray_position(a, layer) - here : vec2(1e30);
    vec2 db = ray_exists(b) ? here - ray_position(b, layer) : vec2(1e30);
    return dot(da, da) <= dot(db, db) ? da : db;
}

// The deposit of ray `index` (read from `layer`) on the plane at `depth`; false when it
// carries no light.
bool ray_deposit(int index, uint layer, float depth, out RayDeposit d) {
    ivec2 c = ivec2(index % int(P.light_rays.x), index / int(P.light_rays.x));
    vec4 lc = READ_RAY(rays_flux, layer, index);
    vec4 lv = READ_RAY(rays_direction, layer, index);
    vec2 here = vec2(lc.w, lv.w);
    d.amplitude = vec4(0.0);
    d.footprint = vec4(0.0);
    d.direction = vec3(0.0);
    if (!(max(lc.r, max(lc.g, lc.b)) > 0.0)) return false;
    // View-space units to pixels on this plane.
    float half_h = depth * P.camera.x;
    vec2 px_per_unit = vec2(P.camera.z / (2.0 * half_h * P.camera.y), P.camera.w / (2.0 * half_h));
    vec2 centre = project(vec3(here, depth)) * P.camera.zw;
    vec2 ei = cell_edge(c, here, ivec2(1, 0), layer) * px_per_unit;
    vec2 ej = cell_edge(c, here, ivec2(0, 1), layer) * px_per_unit;
    // The cell's bounding box, at most 2 * transport.w pixels across (wider cells still
    // deposit all their flux, over that box).
    vec2 w = clamp(abs(ei) + abs(ej), vec2(1e-3), vec2(2.0 * P.transport.w));
    float pixel_area = 1.0 / (px_per_unit.x * px_per_unit.y);
    vec3 a = lc.rgb / (w.x * w.y * pixel_area);
    d.amplitude = vec4(a, dot(a, vec3(0.2126, 0.7152, 0.0722)));
    d.footprint = vec4(centre, w);
    d.direction = normalize(lv.xyz);
    return true;
}

// The area (pixels²) of the deposit's box that pixel `p` (integer corner) covers.
float deposit_overlap(vec4 footprint, vec2 p) {
    vec2 lo = max(footprint.xy - 0.5 * footprint.zw, p);
    vec2 hi = min(footprint.xy + 0.5 * footprint.zw, p + 1.0);
    vec2 overlap = max(hi - lo, vec2(0.0));
    return overlap.x * overlap.y;
}

#endif

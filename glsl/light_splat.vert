#version 460
// Forward light transport, second half of a plane: every light ray, just advanced to this
// plane by sweep_forward.frag, adds its flux to the plane's irradiance image as one point
// sprite (additive blending). The sprite is the ray's cell on this plane (the extent of
// the parallelogram spanned by its neighbouring rays), a box the ray's flux is spread over
// uniformly; each pixel receives the flux of the part of the box it covers (exact area
// overlap). So each ray deposits exactly its flux (power is conserved by construction, up
// to rays that land outside the viewport), evenly spaced rays tile the plane and give an
// exactly uniform field whatever their spacing against the pixels (a tent sampled at the
// pixel centres and normalised per ray rippled by ±10 %, measured), converging rays
// concentrate their flux (a caustic) and crossing rays simply overlap.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    uint pad;
} pc;

layout(location = 0) flat out vec4 amplitude;  // rgb = irradiance per pixel² of overlap, a = luminance
layout(location = 1) flat out vec4 footprint;  // xy = centre (pixels), zw = box widths (pixels)
layout(location = 2) flat out vec3 direction;  // unit light direction

vec2 ray_position(ivec2 c) {
    int r = ray_index(c);
    return vec2(READ_RAY(rays_flux, pc.read_layer, r).w,
                READ_RAY(rays_direction, pc.read_layer, r).w);
}

// The shorter of the two one-sided differences to the neighbours along `axis`: across a
// discontinuity (a silhouette, a shadow edge) the smooth side gives the cell size.
vec2 cell_edge(ivec2 c, vec2 here, ivec2 axis) {
    ivec2 a = c + axis, b = c - axis;
    vec2 da = ray_exists(a) ? ray_position(a) - here : vec2(1e30);
    vec2 db = ray_exists(b) ? here - ray_position(b) : vec2(1e30);
    return dot(da, da) <= dot(db, db) ? da : db;
}

void main() {
    int index = gl_VertexIndex;
    ivec2 c = ivec2(index % int(P.light_rays.x), index / int(P.light_rays.x));
    vec4 lc = READ_RAY(rays_flux, pc.read_layer, index);
    vec4 lv = READ_RAY(rays_direction, pc.read_layer, index);
    vec3 v = lv.xyz;
    vec2 here = vec2(lc.w, lv.w);
    gl_PointSize = 1.0;
    if (!(max(lc.r, max(lc.g, lc.b)) > 0.0)) {
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    // View-space units to pixels on this plane.
    float half_h = pc.depth * P.camera.x;
    vec2 px_per_unit = vec2(P.camera.z / (2.0 * half_h * P.camera.y), P.camera.w / (2.0 * half_h));
    vec2 centre = project(vec3(here, pc.depth)) * P.camera.zw;
    vec2 ei = cell_edge(c, here, ivec2(1, 0)) * px_per_unit;
    vec2 ej = cell_edge(c, here, ivec2(0, 1)) * px_per_unit;
    // The cell's bounding box, at most 2 * transport.w pixels across (wider cells still
    // deposit all their flux, over that box).
    vec2 w = clamp(abs(ei) + abs(ej), vec2(1e-3), vec2(2.0 * P.transport.w));
    float pixel_area = 1.0 / (px_per_unit.x * px_per_unit.y);
    vec3 a = lc.rgb / (w.x * w.y * pixel_area);
    amplitude = vec4(a, dot(a, vec3(0.2126, 0.7152, 0.0722)));
    footprint = vec4(centre, w);
    direction = normalize(v);
    // A box w pixels wide overlaps at most ceil(w) + 1 pixels per axis, all of whose
    // centres lie within (ceil(w) + 1) / 2 of the box's centre: the smallest sprite that
    // covers them (the fragments compute the exact overlap and drop empty pixels; a
    // sprite one pixel wider shaded 9 fragments for the typical sub-pixel box instead of
    // 4, and the splat was 44 % of the forward sweep on lavapipe).
    gl_PointSize = ceil(max(w.x, w.y)) + 1.0;
    gl_Position = vec4(centre / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}

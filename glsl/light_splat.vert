#version 460
// Forward light transport, second half of a plane: every light ray, just advanced to this
// plane by sweep_forward.frag, adds its flux to the plane's irradiance image as one point
// sprite (additive blending). The sprite is a separable tent whose half-widths are the
// ray's cell on this plane (the distance to its neighbouring rays), so evenly spaced rays
// sum to a smooth field, converging rays concentrate their flux (a caustic) and crossing
// rays simply overlap. The tent's samples at the pixel centres are normalised to sum to
// one, so each ray deposits exactly its flux: power is conserved by construction (up to
// rays that land outside the viewport).
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    uint pad;
} pc;

layout(location = 0) flat out vec4 amplitude;  // rgb = flux per unit weight / pixel area, a = luminance
layout(location = 1) flat out vec4 footprint;  // xy = centre (pixels), zw = half-widths (pixels)
layout(location = 2) flat out vec3 direction;  // unit light direction

vec2 ray_position(ivec2 c) {
    return vec2(READ_PIXEL(light_colour, pc.read_layer, c).w,
                READ_PIXEL(light_direction, pc.read_layer, c).w);
}

// The shorter of the two one-sided differences to the neighbours along `axis`: across a
// discontinuity (a silhouette, a shadow edge) the smooth side gives the cell size.
vec2 cell_edge(ivec2 c, vec2 here, ivec2 axis, ivec2 hi) {
    ivec2 a = c + axis, b = c - axis;
    bool has_a = all(lessThanEqual(a, hi));
    bool has_b = all(greaterThanEqual(b, ivec2(0)));
    vec2 da = has_a ? ray_position(a) - here : vec2(1e30);
    vec2 db = has_b ? here - ray_position(b) : vec2(1e30);
    return dot(da, da) <= dot(db, db) ? da : db;
}

// Sum of the tent of half-width h centred at x over the pixel centres k + 0.5.
float tent_sum(float x, float h) {
    float s = 0.0;
    for (float k = ceil(x - h - 0.5); k <= floor(x + h - 0.5); k += 1.0) {
        s += max(0.0, 1.0 - abs(k + 0.5 - x) / h);
    }
    return s;
}

void main() {
    ivec2 size = ivec2(P.camera.zw);
    int index = gl_VertexIndex;
    ivec2 c = ivec2(index % size.x, index / size.x);
    vec4 lc = READ_PIXEL(light_colour, pc.read_layer, c);
    vec3 v = READ_PIXEL(light_direction, pc.read_layer, c).xyz;
    vec2 here = vec2(lc.w, READ_PIXEL(light_direction, pc.read_layer, c).w);
    gl_PointSize = 1.0;
    if (!(max(lc.r, max(lc.g, lc.b)) > 0.0)) {
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    // View-space units to pixels on this plane.
    float half_h = pc.depth * P.camera.x;
    vec2 px_per_unit = vec2(P.camera.z / (2.0 * half_h * P.camera.y), P.camera.w / (2.0 * half_h));
    vec2 centre = project(vec3(here, pc.depth)) * P.camera.zw;
    ivec2 hi = size - 1;
    vec2 ei = cell_edge(c, here, ivec2(1, 0), hi) * px_per_unit;
    vec2 ej = cell_edge(c, here, ivec2(0, 1), hi) * px_per_unit;
    // The cell's bounding box (half-widths = the full cell: tent = box * box).
    vec2 h = clamp(abs(ei) + abs(ej), vec2(1.0), vec2(P.transport.w));
    float norm = tent_sum(centre.x, h.x) * tent_sum(centre.y, h.y);
    float pixel_area = 1.0 / (px_per_unit.x * px_per_unit.y);
    vec3 a = lc.rgb / (norm * pixel_area);
    amplitude = vec4(a, dot(a, vec3(0.2126, 0.7152, 0.0722)));
    footprint = vec4(centre, h);
    direction = normalize(v);
    gl_PointSize = 2.0 * ceil(max(h.x, h.y)) + 2.0;
    gl_Position = vec4(centre / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}

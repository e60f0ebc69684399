// Forward light transport, second half of a plane (the `splat=raster` lever): every light
// ray, just advanced to this plane by sweep_light_forward.frag, adds its deposit (its
// cell's two triangles, or a box: light_splat_ray.glsl) to the plane's irradiance image as
// one point sprite (additive blending) covering the deposit's bounding box. The vertex
// shader computes the deposit, the fragment shader the part of it each pixel receives.
//
// Both stages in one file, so their interface cannot drift apart. The includer defines
// SPRITE_VERTEX (1: the vertex shader, 0: the fragment shader) and SPRITE_CELLS (1: the
// cells deposit, light_splat.*; 0: the boxes deposit, light_splat_boxes.*), and with
// SPRITE_GROUPS 1 the grouped sprites of the `splat=groups` lever (light_splat_groups.*
// for cells, light_splat_groups_boxes.* for boxes: a sprite per group of 2 x 2 rays, the
// deposits read from what light_splat_groups.comp stored; light_splat_groups.glsl). The
// boxes deposit passes only what it uses, 3 varyings instead of 10: llvmpipe sets up
// every varying of every point, and the demo's splat at 256² took 15.0 and 14.3 s with
// all ten against 9.3 and 9.7 s with three (A B A B, the same image to the bit).
#ifndef SPRITE_GROUPS
#define SPRITE_GROUPS 0
#endif
// SPRITE_FROM_LIST 1 (light_splat_group_rays.vert): one ray's sprite, the ray taken from
// the grouped sprites' list of groups too wide for one sprite and its deposit from the
// deposits buffer (light_splat_groups.glsl).
#ifndef SPRITE_FROM_LIST
#define SPRITE_FROM_LIST 0
#endif
#if !SPRITE_CELLS
#define DEPOSIT_BOXES_ONLY 1
#endif
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#if SPRITE_GROUPS || SPRITE_FROM_LIST
#define DEPOSITS_READONLY 1
#include "light_gather.glsl"
#include "light_splat_groups.glsl"
#endif

#if SPRITE_VERTEX
#define SPRITE_VARYING flat out
#else
#define SPRITE_VARYING flat in
#endif

#if SPRITE_GROUPS
#if SPRITE_CELLS
// The group (or, in the indirect draws, the group of the ray) and which of its rays the
// sprite carries (bit k: ray k of group_ray); the fragments read the cells' deposits.
layout(location = 0) SPRITE_VARYING int sprite_group;
layout(location = 1) SPRITE_VARYING uint sprite_rays;
#else
// The boxes of the sprite's rays, as varyings (zero for a ray it does not carry): cheaper
// on lavapipe than fragments reading the deposits buffer (docs/NOTES.md, "Grouped
// sprites").
layout(location = 0) SPRITE_VARYING vec4 group_box[4];
layout(location = 4) SPRITE_VARYING vec4 group_amplitude[4];
layout(location = 8) SPRITE_VARYING vec4 group_direction[4];
#endif

#if SPRITE_VERTEX
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;
    uint pad;   // 0: the indirect draws of a point per group; 1: of a point per ray
    vec2 region[8];   // the viewing rays' polygon (sweep_region.vert), unused here
} pc;

void main() {
    int g;
    vec4 fp;
#if !SPRITE_CELLS
    uint sprite_rays;
#endif
    if (pc.pad == 0u) {
        // The indirect draw of workgroup w lists its sprites from slot
        // SPLAT_GROUP_WORKGROUP * w on (light_splat_groups.glsl).
        g = int(sprite_fallback[gl_VertexIndex]);
        fp = sprite_groups[g];
        sprite_rays = 15u;
    } else {
        // The indirect draw of workgroup w starts at vertex 4 * SPLAT_GROUP_WORKGROUP * w.
        int per = 4 * int(SPLAT_GROUP_WORKGROUP);
        int w = gl_VertexIndex / per, v = gl_VertexIndex % per;
        g = int(sprite_fallback[int(SPLAT_GROUP_WORKGROUP) * w + v / 4]);
        ivec2 c = group_ray(g, v % 4);
        fp = ray_exists(c) ? stored_footprint(ray_index(c)) : vec4(0.0);
        sprite_rays = 1u << uint(v % 4);
    }
#if SPRITE_CELLS
    sprite_group = g;
#else
    for (int k = 0; k < 4; ++k) {
        ivec2 c = group_ray(g, k);
        bool carried = (sprite_rays & (1u << uint(k))) != 0u && ray_exists(c);
        RayDeposit d;
        if (carried) {
            d = load_deposit(ray_index(c));
        } else {
            clear_deposit(d);
        }
        group_box[k] = d.box;
        group_amplitude[k] = d.box_amplitude;
        group_direction[k] = vec4(d.direction, 0.0);
    }
#endif
    gl_PointSize = 1.0;
    if (!deposits_anything(fp)) {
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    // As for one ray's sprite, below.
    vec2 w = fp.zw - fp.xy;
    gl_PointSize = ceil(max(w.x, w.y)) + 1.0;
    vec2 centre = 0.5 * (fp.xy + fp.zw);
    gl_Position = vec4(centre / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}
#else
layout(location = 0) out vec4 out_irradiance;
layout(location = 1) out vec4 out_direction;

void main() {
    vec3 e = vec3(0.0);
    vec4 dir = vec4(0.0);
    for (int k = 0; k < 4; ++k) {
#if SPRITE_CELLS
        ivec2 c = group_ray(sprite_group, k);
        if ((sprite_rays & (1u << uint(k))) == 0u || !ray_exists(c)) continue;
        RayDeposit d = load_deposit(ray_index(c));
#else
        RayDeposit d;
        clear_deposit(d);
        d.box = group_box[k];
        d.footprint = group_box[k];
        d.box_amplitude = group_amplitude[k];
        d.direction = group_direction[k].xyz;
#endif
        vec3 ek;
        vec4 dk;
        deposit_at(d, floor(gl_FragCoord.xy), 1.0, ek, dk);
        e += ek;
        dir += dk;
    }
    if (!(dir.w > 0.0) && !(max(e.r, max(e.g, e.b)) > 0.0)) discard;
    out_irradiance = vec4(e, 0.0);
    out_direction = dir;
}
#endif
#else
// The boxes deposit's footprint is its box (box_of_ray).
layout(location = 0) SPRITE_VARYING vec4 box;
layout(location = 1) SPRITE_VARYING vec4 box_amplitude;
layout(location = 2) SPRITE_VARYING vec3 direction;
#if SPRITE_CELLS
layout(location = 3) SPRITE_VARYING vec4 footprint;
layout(location = 4) SPRITE_VARYING vec4 flux_a;
layout(location = 5) SPRITE_VARYING vec4 flux_b;
layout(location = 6) SPRITE_VARYING vec4 flux_c;
layout(location = 7) SPRITE_VARYING vec4 flux_d;
layout(location = 8) SPRITE_VARYING vec4 corners_ab;
layout(location = 9) SPRITE_VARYING vec4 corners_cd;
#endif

#if SPRITE_VERTEX
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    uint pad;
    vec2 region[8];    // the viewing rays' polygon (sweep_region.vert), unused here
} pc;

void main() {
    RayDeposit d;
    gl_PointSize = 1.0;
#if SPRITE_FROM_LIST
    // The indirect draw of workgroup w starts at vertex 4 * SPLAT_GROUP_WORKGROUP * w
    // (light_splat_groups.glsl); 4 vertices per listed group, one per ray.
    int per = 4 * int(SPLAT_GROUP_WORKGROUP);
    int wg = gl_VertexIndex / per, v = gl_VertexIndex % per;
    int g = int(sprite_fallback[int(SPLAT_GROUP_WORKGROUP) * wg + v / 4]);
    ivec2 c = group_ray(g, v % 4);
    bool listed = ray_exists(c);
    if (listed) {
        d = load_deposit(ray_index(c));
    } else {
        clear_deposit(d);
    }
    if (!listed || !deposits_anything(d.footprint)) {
#else
    if (!ray_deposit(gl_VertexIndex, pc.read_layer, pc.depth, d)) {
#endif
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    box = d.box;
    box_amplitude = d.box_amplitude;
    direction = d.direction;
#if SPRITE_CELLS
    footprint = d.footprint;
    flux_a = d.flux_a;
    flux_b = d.flux_b;
    flux_c = d.flux_c;
    flux_d = d.flux_d;
    corners_ab = d.corners_ab;
    corners_cd = d.corners_cd;
#endif
    // A deposit w pixels wide overlaps at most ceil(w) + 1 pixels per axis, all of whose
    // centres lie within (ceil(w) + 1) / 2 of its centre: the smallest sprite that
    // covers them (the fragments compute the exact overlap and drop empty pixels; a
    // sprite one pixel wider shades 9 fragments for the typical sub-pixel box, not 4).
    vec2 w = d.footprint.zw - d.footprint.xy;
    gl_PointSize = ceil(max(w.x, w.y)) + 1.0;
    vec2 centre = 0.5 * (d.footprint.xy + d.footprint.zw);
    gl_Position = vec4(centre / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}
#else
layout(location = 0) out vec4 out_irradiance;
layout(location = 1) out vec4 out_direction;

void main() {
    RayDeposit d;
    clear_deposit(d);
    d.box = box;
    d.box_amplitude = box_amplitude;
    d.direction = direction;
#if SPRITE_CELLS
    d.footprint = footprint;
    d.flux_a = flux_a;
    d.flux_b = flux_b;
    d.flux_c = flux_c;
    d.flux_d = flux_d;
    d.corners_ab = corners_ab;
    d.corners_cd = corners_cd;
#else
    d.footprint = box;
#endif
    vec3 e;
    vec4 dir;
    deposit_at(d, floor(gl_FragCoord.xy), 1.0, e, dir);
    if (!(dir.w > 0.0) && !(max(e.r, max(e.g, e.b)) > 0.0)) discard;
    out_irradiance = vec4(e, 0.0);
    out_direction = dir;
}
#endif
#endif

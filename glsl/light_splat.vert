#version 460
// Forward light transport, second half of a plane (the `splat=raster` lever): every light
// ray, just advanced to this plane by sweep_light_forward.frag, adds its deposit (its
// cell's two triangles, or a box: light_splat_ray.glsl) to the plane's irradiance image as
// one point sprite (additive blending) covering the deposit's bounding box.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    uint pad;
} pc;

layout(location = 0) flat out vec4 flux_a;
layout(location = 1) flat out vec4 flux_b;
layout(location = 2) flat out vec4 footprint;
layout(location = 3) flat out vec4 corners_ab;
layout(location = 4) flat out vec4 corners_cd;
layout(location = 5) flat out vec3 direction;
layout(location = 6) flat out vec4 box_amplitude;
layout(location = 7) flat out vec4 box;
layout(location = 8) flat out vec4 flux_c;
layout(location = 9) flat out vec4 flux_d;

void main() {
    RayDeposit d;
    gl_PointSize = 1.0;
    if (!ray_deposit(gl_VertexIndex, pc.read_layer, pc.depth, d)) {
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    flux_a = d.flux_a;
    flux_b = d.flux_b;
    flux_c = d.flux_c;
    flux_d = d.flux_d;
    footprint = d.footprint;
    corners_ab = d.corners_ab;
    corners_cd = d.corners_cd;
    direction = d.direction;
    box_amplitude = d.box_amplitude;
    box = d.box;
    // A deposit w pixels wide overlaps at most ceil(w) + 1 pixels per axis, all of whose
    // centres lie within (ceil(w) + 1) / 2 of its centre: the smallest sprite that
    // covers them (the fragments compute the exact overlap and drop empty pixels; a
    // sprite one pixel wider shaded 9 fragments for the typical sub-pixel box instead of
    // 4, and the splat was 44 % of the forward sweep on lavapipe).
    vec2 w = d.footprint.zw - d.footprint.xy;
    gl_PointSize = ceil(max(w.x, w.y)) + 1.0;
    vec2 centre = 0.5 * (d.footprint.xy + d.footprint.zw);
    gl_Position = vec4(centre / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}

#version 460
// Forward light transport, second half of a plane (the `splat=raster` lever): every light
// ray, just advanced to this plane by sweep_light_forward.frag, adds its flux to the
// plane's irradiance image as one point sprite (additive blending) covering its deposit
// box (light_splat_ray.glsl).
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

layout(location = 0) flat out vec4 amplitude;
layout(location = 1) flat out vec4 footprint;
layout(location = 2) flat out vec3 direction;

void main() {
    RayDeposit d;
    gl_PointSize = 1.0;
    if (!ray_deposit(gl_VertexIndex, pc.read_layer, pc.depth, d)) {
        gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);   // nothing to deposit: clipped
        return;
    }
    amplitude = d.amplitude;
    footprint = d.footprint;
    direction = d.direction;
    // A box w pixels wide overlaps at most ceil(w) + 1 pixels per axis, all of whose
    // centres lie within (ceil(w) + 1) / 2 of the box's centre: the smallest sprite that
    // covers them (the fragments compute the exact overlap and drop empty pixels; a
    // sprite one pixel wider shaded 9 fragments for the typical sub-pixel box instead of
    // 4, and the splat was 44 % of the forward sweep on lavapipe).
    gl_PointSize = ceil(max(d.footprint.z, d.footprint.w)) + 1.0;
    gl_Position = vec4(d.footprint.xy / P.camera.zw * 2.0 - 1.0, 0.0, 1.0);
}

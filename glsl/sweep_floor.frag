#version 460
// Benchmark floor of the plane sweep (`SweepOptions::floor`): the same render pass, the
// same six attachments, barriers and sampled reads of the previous plane as sweep.frag,
// but each state texel is only carried forward. Its time per plane is the cost of moving
// the state buffers on this device; sweep time / floor time is how much the optics cost
// on top of that.
#extension GL_GOOGLE_include_directive : require
#include "sweep_buffers.glsl"

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;
    uint pad;
} pc;

layout(location = 0) out vec4 out_light_colour;
layout(location = 1) out vec4 out_light_direction;
layout(location = 2) out vec4 out_view_position;
layout(location = 3) out vec4 out_view_direction;
layout(location = 4) out vec4 out_colour_opacity;
layout(location = 5) out vec4 out_medium;

// Read like the plane shaders read their own pixel (per the `arrays` lever).
#define CARRY(name) READ_PIXEL(name, pc.read_layer, p)

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    out_light_colour = CARRY(light_colour);
    out_light_direction = CARRY(light_direction);
    // Advance the view position by one plane so the work depends on the plane.
    out_view_position = CARRY(view_position) + vec4(0.0, 0.0, pc.depth * 1e-9, 0.0);
    out_view_direction = CARRY(view_direction);
    out_colour_opacity = CARRY(colour_opacity);
    out_medium = CARRY(medium);
}

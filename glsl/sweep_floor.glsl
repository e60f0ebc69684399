// Benchmark floor of the plane sweep (`SweepOptions::floor`): the same render pass, the
// same five attachments (the backward transport's compact state, sweep_plane_io.glsl),
// barriers and sampled reads of the previous plane as sweep.frag, but each state texel is
// only carried forward. Its time per plane is the cost of moving
// the state buffers on this device; sweep time / floor time is how much the optics cost
// on top of that.
#include "sweep_buffers.glsl"

#include "sweep_plane_io.glsl"

BACKWARD_STATE_OUTPUTS;
#define STORE_OUTPUTS(at) STORE_BACKWARD_STATE(at)

// Read like the plane shaders read their own pixel (per the `arrays` lever).
#define CARRY(name) READ_PIXEL(name, pc.read_layer, p)

void PLANE_MAIN() {
    ivec2 p = ivec2(FRAG_XY);
    // Move the viewing ray's x by a hair so the work depends on the plane.
    out_light_colour = CARRY(light_colour) + vec4(0.0, 0.0, 0.0, pc.depth * 1e-9);
    out_light_direction = CARRY(light_direction);
    out_view_direction = CARRY(view_direction);
    out_colour_opacity = CARRY(colour_opacity);
    out_medium = CARRY(medium);
}

COMPUTE_ENTRY

// Benchmark floor of the plane sweep (`SweepOptions::floor`): the same render pass, the
// same six attachments, barriers and sampled reads of the previous plane as sweep.frag,
// but each state texel is only carried forward. Its time per plane is the cost of moving
// the state buffers on this device; sweep time / floor time is how much the optics cost
// on top of that.
#include "sweep_buffers.glsl"

#include "sweep_plane_io.glsl"

SIX_STATE_OUTPUTS;
#define STORE_OUTPUTS(at) STORE_SIX_STATES(at)

// Read like the plane shaders read their own pixel (per the `arrays` lever).
#define CARRY(name) READ_PIXEL(name, pc.read_layer, p)

void PLANE_MAIN() {
    ivec2 p = ivec2(FRAG_XY);
    out_light_colour = CARRY(light_colour);
    out_light_direction = CARRY(light_direction);
    // Advance the view position by one plane so the work depends on the plane.
    out_view_position = CARRY(view_position) + vec4(0.0, 0.0, pc.depth * 1e-9, 0.0);
    out_view_direction = CARRY(view_direction);
    out_colour_opacity = CARRY(colour_opacity);
    out_medium = CARRY(medium);
}

COMPUTE_ENTRY

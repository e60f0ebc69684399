#version 460
// Backend self-test: writes the push-constant colour (tests/graphics.rs).
layout(push_constant) uniform Push { vec4 colour; } pc;
layout(location = 0) out vec4 out_colour;
void main() { out_colour = pc.colour; }

#version 460
// Backend self-test of the ping-pong pattern (tests/graphics.rs): reads the previous plane's
// layer through one of two per-layer views chosen by push constant, writes it plus one.
layout(set = 0, binding = 0) uniform sampler2D layer0;
layout(set = 0, binding = 1) uniform sampler2D layer1;
layout(push_constant) uniform Push { uint read_layer; } pc;
layout(location = 0) out vec4 out_colour;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 prev = pc.read_layer == 0u ? texelFetch(layer0, p, 0) : texelFetch(layer1, p, 0);
    out_colour = prev + vec4(1.0);
}

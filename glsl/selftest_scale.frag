#version 460
// Backend self-test: samples another layer of the same image array, scaled by the push
// constant, plus the pixel position so a misplaced sample would show (tests/graphics.rs).
layout(set = 0, binding = 0) uniform sampler2D source;
layout(push_constant) uniform Push { vec4 scale; } pc;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 out_colour;
void main() { out_colour = texelFetch(source, ivec2(gl_FragCoord.xy), 0) * pc.scale + vec4(gl_FragCoord.xy, 0.0, 0.0); }

#version 460
// Display pass: the renderer's linear HDR frame -> tone mapped, sRGB-encoded 8-bit colour,
// the same arithmetic as output::ToneMap::apply and output::linear_to_srgb on the CPU (the
// PNG path), so the window shows what `refrakt render -o x.png` writes (tests/viewer.rs).
layout(set = 0, binding = 0) uniform sampler2D frame;   // RGBA32F, texelFetch only
layout(push_constant) uniform Push {
    float scale;        // 2^exposure
    uint op;            // 0 none (clamp), 1 Reinhard, 2 ACES (Narkowicz)
    uint encode_srgb;   // 1: encode here (UNORM target); 0: the target format encodes
    uint pad;
} pc;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 out_colour;

float tone(float c) {
    float x = max(c, 0.0) * pc.scale;
    if (pc.op == 0u) return min(x, 1.0);
    if (pc.op == 1u) return x / (1.0 + x);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

float srgb(float c) {
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

void main() {
    vec4 p = texelFetch(frame, ivec2(gl_FragCoord.xy), 0);
    vec3 t = vec3(tone(p.r), tone(p.g), tone(p.b));
    if (pc.encode_srgb == 1u) t = vec3(srgb(t.r), srgb(t.g), srgb(t.b));
    out_colour = vec4(t, clamp(p.a, 0.0, 1.0));
}

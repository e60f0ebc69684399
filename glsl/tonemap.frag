#version 460
// Display pass: the renderer's linear HDR frame -> tone mapped, sRGB-encoded 8-bit colour,
// the same arithmetic as output::ToneMap::apply and output::linear_to_srgb on the CPU (the
// PNG path), so the window shows what `refrakt render -o x.png` writes (tests/viewer.rs).
// A source smaller than the target (the viewer's previews) is magnified bilinearly between
// its pixel centres; at equal sizes each pixel is its source texel. The viewer's axes
// marker is drawn over the bottom-left corner.
layout(set = 0, binding = 0) uniform sampler2D frame;   // RGBA32F, texelFetch only
layout(push_constant) uniform Push {
    float scale;        // 2^exposure
    uint op;            // 0 none (clamp), 1 Reinhard, 2 ACES (Narkowicz)
    uint encode_srgb;   // 1: encode here (UNORM target); 0: the target format encodes
    uint axes;          // 1: draw the axes marker
    uvec2 target;       // the target's size in pixels
    uvec2 pad;
    vec4 axis[3];       // world x, y, z on the screen: (right, down, towards the viewer)
} pc;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 out_colour;

float tone(float c) {
    // Capped where every operator is white, as tone.rs' WHITE_CAP: ACES' x² overflows
    // above ~1.8e19, and NaN would turn the brightest pixels black.
    float x = min(max(c, 0.0) * pc.scale, 1e9);
    if (pc.op == 0u) return min(x, 1.0);
    if (pc.op == 1u) return x / (1.0 + x);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

float srgb(float c) {
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

vec4 source_pixel() {
    ivec2 size = textureSize(frame, 0);
    if (size == ivec2(pc.target)) return texelFetch(frame, ivec2(gl_FragCoord.xy), 0);
    vec2 x = gl_FragCoord.xy * vec2(size) / vec2(pc.target) - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 t = x - vec2(i);
    ivec2 hi = size - 1;
    vec4 a = texelFetch(frame, clamp(i, ivec2(0), hi), 0);
    vec4 b = texelFetch(frame, clamp(i + ivec2(1, 0), ivec2(0), hi), 0);
    vec4 c = texelFetch(frame, clamp(i + ivec2(0, 1), ivec2(0), hi), 0);
    vec4 d = texelFetch(frame, clamp(i + ivec2(1, 1), ivec2(0), hi), 0);
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}

// The axes marker: three lines from a point 36 px in from the bottom-left corner, each 26 px
// times its axis' length on the screen; an axis pointing away from the viewer is drawn
// darker, and the nearest axis wins where lines cross. Its colours are set after tone
// mapping, before the sRGB encoding.
const float MARKER_CENTRE = 36.0;
const float MARKER_LENGTH = 26.0;
bool axes_marker(out vec3 colour) {
    vec2 c = vec2(MARKER_CENTRE, float(pc.target.y) - MARKER_CENTRE);
    vec2 p = gl_FragCoord.xy - c;
    float best_depth = -2.0;
    bool hit = false;
    for (int k = 0; k < 3; ++k) {
        vec2 e = pc.axis[k].xy * MARKER_LENGTH;
        float h = clamp(dot(p, e) / max(dot(e, e), 1e-6), 0.0, 1.0);
        if (length(p - e * h) <= 1.25 && pc.axis[k].z > best_depth) {
            best_depth = pc.axis[k].z;
            vec3 base = vec3(k == 0 ? 1.0 : 0.15, k == 1 ? 1.0 : 0.15, k == 2 ? 1.0 : 0.15);
            colour = base * (pc.axis[k].z < 0.0 ? 0.55 : 1.0);
            hit = true;
        }
    }
    return hit;
}

void main() {
    vec4 p = source_pixel();
    vec3 t = vec3(tone(p.r), tone(p.g), tone(p.b));
    if (pc.axes == 1u) {
        vec3 marker;
        if (axes_marker(marker)) {
            t = marker;
            p.a = 1.0;
        }
    }
    if (pc.encode_srgb == 1u) t = vec3(srgb(t.r), srgb(t.g), srgb(t.b));
    out_colour = vec4(t, clamp(p.a, 0.0, 1.0));
}

#version 460
// See light_splat.vert: the part of one light ray's box that this pixel covers.
layout(location = 0) flat in vec4 amplitude;
layout(location = 1) flat in vec4 footprint;
layout(location = 2) flat in vec3 direction;

layout(location = 0) out vec4 out_irradiance;
layout(location = 1) out vec4 out_direction;

void main() {
    vec2 lo = max(footprint.xy - 0.5 * footprint.zw, gl_FragCoord.xy - 0.5);
    vec2 hi = min(footprint.xy + 0.5 * footprint.zw, gl_FragCoord.xy + 0.5);
    vec2 overlap = max(hi - lo, vec2(0.0));
    float w = overlap.x * overlap.y;
    if (w <= 0.0) discard;
    out_irradiance = vec4(amplitude.rgb * w, 0.0);
    out_direction = vec4(direction * (amplitude.a * w), amplitude.a * w);
}

#version 460
// See light_splat.vert: one light ray's tent, weighted at this pixel's centre.
layout(location = 0) flat in vec4 amplitude;
layout(location = 1) flat in vec4 footprint;
layout(location = 2) flat in vec3 direction;

layout(location = 0) out vec4 out_irradiance;
layout(location = 1) out vec4 out_direction;

void main() {
    vec2 d = abs(gl_FragCoord.xy - footprint.xy) / footprint.zw;
    float w = max(0.0, 1.0 - d.x) * max(0.0, 1.0 - d.y);
    if (w <= 0.0) discard;
    out_irradiance = vec4(amplitude.rgb * w, 0.0);
    out_direction = vec4(direction * (amplitude.a * w), amplitude.a * w);
}

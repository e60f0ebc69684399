#version 460
// Composite pass: the background seen through the volume's remaining transmittance and
// medium filter (Oddy-Willis, as in the EA baseline). The environment map (issue 5) will
// replace the constant background using the final viewing-ray directions.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { uint layer; } pc;
layout(set = 0, binding = 16, rgba32f) uniform writeonly image2D frame;

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(id, ivec2(P.camera.zw)))) return;
    vec4 CA = READ_PIXEL(colour_opacity, pc.layer, id);
    vec3 M = READ_PIXEL(medium, pc.layer, id).rgb;
    vec3 rgb = CA.rgb + (1.0 - CA.a) * M * P.background.rgb;
    float a = CA.a + (1.0 - CA.a) * P.background.a;
    imageStore(frame, id, vec4(rgb, a));
}

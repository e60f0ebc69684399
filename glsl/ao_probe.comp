#version 460
// The ambient occlusion of ao.glsl at a list of points (texture coordinates), one per
// invocation: the shader-side check of the AO model against closed forms (tests/ao.rs).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform usampler3D sat_table;
layout(std430, set = 0, binding = 1) readonly buffer Points {
    vec4 points[];  // xyz: texture coordinates
};
layout(std430, set = 0, binding = 2) writeonly buffer Results {
    float results[];
};
layout(push_constant) uniform Push {
    ivec4 dims;  // xyz: the volume's size in voxels, w: shells
    float inv_scale;
    uint count;
} pc;

#define SAT3D_LOAD(p) texelFetch(sat_table, p, 0).xy
#define SAT3D_DIMS pc.dims.xyz
#define SAT3D_INV_SCALE pc.inv_scale
#include "sat3d.glsl"
#include "ao.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    results[i] = ao_transmittance(points[i].xyz, pc.dims.w);
}

#version 460
// Box averages from the 3D summed-area table through glsl/sat3d.glsl, one per invocation,
// for a list of boxes: the read side's check (tests/sat3d.rs) and an example of its use.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform usampler3D sat_table;
layout(std430, set = 0, binding = 1) readonly buffer Boxes {
    ivec4 boxes[];  // pairs: lo.xyz, hi.xyz (inclusive voxel indices)
};
layout(std430, set = 0, binding = 2) writeonly buffer Averages {
    float averages[];
};
layout(push_constant) uniform Push {
    ivec4 dims;  // xyz: the volume's size in voxels
    float inv_scale;
    uint count;
} pc;

#define SAT3D_LOAD(p) texelFetch(sat_table, p, 0).xy
#define SAT3D_DIMS pc.dims.xyz
#define SAT3D_INV_SCALE pc.inv_scale
#include "sat3d.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    averages[i] = sat_box_average(boxes[2 * i].xyz, boxes[2 * i + 1].xyz);
}

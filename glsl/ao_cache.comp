#version 460
// The AO model's occlusion cache (render/ao): ao.glsl's transmittance at every voxel
// centre, rebuilt when the extinction (transfer functions) or the radius changes and
// sampled trilinearly by ao.comp. Evaluated per sample instead, the occlusion is constant
// over each voxel (its cubes are whole voxels around the sample's voxel) and a lit surface
// showed the voxel grid; cached, a sample costs one fetch instead of 8 per cube (as Ament et
// al. cache their ambient extinction volume).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform usampler3D sat_table;
layout(set = 0, binding = 1, r32f) uniform writeonly image3D occlusion;

layout(push_constant) uniform Push {
    ivec4 dims;  // xyz: the volume's size in voxels, w: shells
    float inv_scale;
} pc;

#define SAT3D_LOAD(p) texelFetch(sat_table, p, 0).xy
#define SAT3D_DIMS pc.dims.xyz
#define SAT3D_INV_SCALE pc.inv_scale
#include "sat3d.glsl"
#include "ao.glsl"

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, pc.dims.xyz))) return;
    vec3 tex = (vec3(v) + 0.5) / vec3(pc.dims.xyz);
    imageStore(occlusion, v, vec4(ao_transmittance(tex, pc.dims.w), 0.0, 0.0, 0.0));
}

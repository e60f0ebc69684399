#version 460
// The ambient extinction volume of the ambient-scattering model (render/ambient; Ament et
// al. sect. 4.2.1, eqs. 5, 12-13): at every voxel centre the mean extinction over the cube
// with the volume of the ambient sphere S_r, side a = r (4 pi / 3)^(1/3) voxels, from the
// extinction volume's 3D summed-area table (sat3d.glsl: the outside of the volume counts as
// empty). The table holds whole-voxel cubes of odd side 2k + 1 centred on the voxel; a
// fractional side is the mean of the two whole cubes around it, weighted linearly in the
// side (exact for a homogeneous medium, so a uniform block keeps its extinction). Rebuilt
// when the extinction (transfer functions) or the radius changes.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform usampler3D sat_table;
layout(set = 0, binding = 1, r32f) uniform writeonly image3D ambient_extinction;

layout(push_constant) uniform Push {
    ivec4 dims;  // xyz: the volume's size in voxels
    float inv_scale;
    float side;  // the cube's side a in voxels
} pc;

#define SAT3D_LOAD(p) texelFetch(sat_table, p, 0).xy
#define SAT3D_DIMS pc.dims.xyz
#define SAT3D_INV_SCALE pc.inv_scale
#include "sat3d.glsl"

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, pc.dims.xyz))) return;
    // Below one voxel the sphere lies inside the sample's voxel: its own extinction.
    float a = max(pc.side, 1.0);
    int k = int(floor((a - 1.0) * 0.5));
    float w = (a - float(2 * k + 1)) * 0.5;
    float inner = sat_box_average(v - k, v + k);
    float outer = w > 0.0 ? sat_box_average(v - (k + 1), v + (k + 1)) : inner;
    imageStore(ambient_extinction, v, vec4(mix(inner, outer, w), 0.0, 0.0, 0.0));
}

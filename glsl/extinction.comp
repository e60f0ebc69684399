#version 460
// The extinction volume of the ambient models (render/ao): per voxel, the extinction
// coefficient the transfer function gives its value, per reference step (the smallest
// voxel side): sigma_t = -ln(1 - alpha_tf), the inverse of eq. 3.13's opacity of one step.
// An opaque value (alpha 1) would be infinite: alpha is held below 1 - 1e-6, i.e. at most
// 13.8 per voxel, a transmittance of 1e-6 across one voxel - opaque for any picture.
// Rebuilt when the volume or the transfer functions change; its 3D summed-area table
// (render/sat3d.rs) gives box averages of it in O(1).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1) uniform sampler1DArray tf;
layout(set = 0, binding = 2, r32f) uniform writeonly image3D extinction;

void main() {
    ivec3 dims = imageSize(extinction);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, dims))) return;
    float s = texelFetch(volume, v, 0).r;
    float alpha = textureLod(tf, vec2(tf_coord(s), 0.0), 0.0).a;
    float sigma = -log(1.0 - min(alpha, 1.0 - 1e-6));
    imageStore(extinction, v, vec4(sigma, 0.0, 0.0, 0.0));
}

#version 460
// The field texture (the sweep's `field` lever, render/field.rs): per voxel, the scalar
// value and the gradient of eta = eta_tf(value) by central differences one voxel apart in
// texture coordinates (eq. 3.16, thesis sect. 5.2: eta_tf applied to the neighbours before
// differencing), exactly what glsl/sweep_common.glsl sample_field computes at a voxel
// centre from seven volume fetches and six transfer-function lookups. Sampled trilinearly
// it replaces those thirteen fetches with one. Outside the volume the value is zero, as
// value_at_tex samples it. The eta scale k of the render options is applied by the
// sampler (grad eta' = k grad eta_tf), so only the volume and the transfer functions make
// this texture: it is rebuilt when either changes.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1) uniform sampler1DArray tf;   // layer 1 .a = eta
layout(set = 0, binding = 2, rgba32f) uniform writeonly image3D field;

float value_at(ivec3 v, ivec3 dims) {
    if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, dims))) return 0.0;
    return texelFetch(volume, v, 0).r;
}

float eta_tf(float s) {
    return textureLod(tf, vec2(tf_coord(s), 1.0), 0.0).a;
}

void main() {
    ivec3 dims = imageSize(field);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, dims))) return;
    vec3 h = 1.0 / vec3(dims);
    vec3 ge;
    for (int k = 0; k < 3; ++k) {
        ivec3 e = ivec3(0);
        e[k] = 1;
        ge[k] = (eta_tf(value_at(v + e, dims)) - eta_tf(value_at(v - e, dims))) / (2.0 * h[k]);
    }
    imageStore(field, v, vec4(value_at(v, dims), ge));
}

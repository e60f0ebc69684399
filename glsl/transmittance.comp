#version 460
// The single-scattering model's transmittance cache (render/single): per voxel, the
// fraction of the directional light that reaches the voxel's centre through the volume,
// T = exp(-integral of sigma_t from the centre to where the light enters the box), by
// the midpoint rule over the extinction volume (glsl/extinction.comp, sigma_t per
// reference step; trilinear between voxel centres) in steps of at most half a reference
// step; the box's outside is empty. Rebuilt when the transfer functions (through the
// extinction volume) or the light's direction change.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler3D extinction;
layout(set = 0, binding = 1, r32f) uniform writeonly image3D transmittance;

layout(push_constant) uniform Push {
    vec4 towards;      // xyz = unit direction towards the light (world), w = reference step
    vec4 half_extent;  // xyz = the box's half extent (world)
} pc;

void main() {
    ivec3 dims = imageSize(transmittance);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, dims))) return;
    vec3 half_extent = pc.half_extent.xyz;
    vec3 d = pc.towards.xyz;
    vec3 x = ((vec3(v) + 0.5) / vec3(dims) - 0.5) * 2.0 * half_extent;
    // Distance from x along d to the box's face.
    vec3 inv = 1.0 / d;
    vec3 t1 = max((half_extent - x) * inv, (-half_extent - x) * inv);
    float t_exit = max(min(min(t1.x, t1.y), t1.z), 0.0);
    float ref_step = pc.towards.w;
    int n = int(ceil(t_exit / (0.5 * ref_step)));
    float dt = n > 0 ? t_exit / float(n) : 0.0;
    float tau = 0.0;
    for (int i = 0; i < n; ++i) {
        vec3 p = x + (float(i) + 0.5) * dt * d;
        tau += texture(extinction, p / (2.0 * half_extent) + 0.5).r;
    }
    tau *= dt / ref_step;
    imageStore(transmittance, v, vec4(exp(-tau), 0.0, 0.0, 0.0));
}

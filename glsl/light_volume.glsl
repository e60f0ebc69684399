// The eikonal light simulator's light volume (render/light_simulator.rs, render/eikonal):
// per voxel of the volume's grid (x fastest), the fluence rgb, then the luminance-weighted
// mean light direction xyz (world space; shorter than 1 where several wavefronts cross a
// voxel, zero where no light arrives). Read by the eikonal view (glsl/eikonal_view.comp)
// and by the sweep's viewing rays with `--light-transport eikonal` (glsl/sweep_light.glsl).
//
// The includer defines LIGHT_VOLUME, the buffer's vec4 array.
#ifndef REFRAKT_LIGHT_VOLUME_GLSL
#define REFRAKT_LIGHT_VOLUME_GLSL

#ifndef LIGHT_VOLUME
#error "define LIGHT_VOLUME (the light volume's vec4 array) before including light_volume.glsl"
#endif

// The fluence and mean direction at texture coordinate t of the box ([0, 1]^3), dims the
// voxels per axis: trilinear between voxel centres (the simulator's deposit grid), clamped
// to the edge voxels.
void light_volume_at(vec3 t, vec3 dims, out vec3 fluence, out vec3 direction) {
    vec3 g = clamp(t * dims - 0.5, vec3(0.0), dims - 1.0);
    ivec3 d = ivec3(dims);
    ivec3 b = max(min(ivec3(floor(g)), d - 2), ivec3(0));
    vec3 f = g - vec3(b);
    fluence = vec3(0.0);
    direction = vec3(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 c = min(b + o, d - 1);
        vec3 wv = mix(1.0 - f, f, vec3(o));
        float wt = wv.x * wv.y * wv.z;
        uint vox = uint((c.z * d.y + c.y) * d.x + c.x);
        fluence += wt * LIGHT_VOLUME[2u * vox].rgb;
        direction += wt * LIGHT_VOLUME[2u * vox + 1u].xyz;
    }
}

#endif

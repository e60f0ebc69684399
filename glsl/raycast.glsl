// Camera rays and the volume box, shared by the ray marchers (ea.comp, ao.comp).
#ifndef REFRAKT_RAYCAST_GLSL
#define REFRAKT_RAYCAST_GLSL

// The unit direction through pixel `id` of a `size` image; cam_pos.w = tan(fov_y / 2),
// cam_forward.w = aspect (width / height).
vec3 camera_ray(uvec2 id, uvec2 size, vec4 cam_pos, vec4 cam_forward, vec3 right, vec3 up) {
    vec2 ndc = (vec2(id) + 0.5) / vec2(size) * 2.0 - 1.0;
    return normalize(cam_forward.xyz
        + ndc.x * cam_pos.w * cam_forward.w * right
        - ndc.y * cam_pos.w * up);
}

// Slab test against the box [-half, half]: the ray's entry (not before 0) and exit
// distances; it meets the box when t_far > t_near.
void box_span(vec3 eye, vec3 dir, vec3 half_extent, out float t_near, out float t_far) {
    vec3 inv = 1.0 / dir;
    vec3 t0 = (-half_extent - eye) * inv;
    vec3 t1 = (half_extent - eye) * inv;
    vec3 tmin = min(t0, t1), tmax = max(t0, t1);
    t_near = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    t_far = min(min(tmax.x, tmax.y), tmax.z);
}

#endif

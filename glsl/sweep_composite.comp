#version 460
// Composite (thesis sect. 4.4, 5.3): the environment behind the volume, seen through its
// remaining transmittance and medium (Oddy-Willis): C + (1 - A) M env. A pixel whose
// viewing ray left the volume bent averages the map over the footprint of its own and
// three neighbours' final directions with the summed-area table; a ray that was never bent
// sees the map sharply. Without an environment, the constant background.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "environment.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
// Mirrored by render::refract::CompositePush.
layout(push_constant) uniform Push {
    uint layer;                // the layer the last plane wrote
    uint volume_reflections;   // 1: the first face's reflection sees the volume
    uint record_stride;        // the light record keeps every record_stride-th plane
    uint have_gradient;        // 1: the smoothed gradient volume is bound (binding 15)
    uint light_from_volume;    // 1: the eikonal transport's light volume (binding 16)
} pc;
layout(set = 0, binding = 10, rgba32f) uniform writeonly image2D frame;
layout(set = 0, binding = 11) uniform sampler2D env_map;
layout(set = 0, binding = 12) uniform sampler2D env_sat;
layout(set = 0, binding = 13) uniform EnvParams {
    vec4 info;   // x = 1 when a map is used, y = rotation about world up (radians),
                 // z = 1 for the SAT footprint, 0 for a single bilinear lookup
    vec4 mean;   // the SAT's mean offset
} E;

#include "sweep_reflect.glsl"

// What lies outside the volume in view-space direction d, read at a point: the map
// (rotated about world up) or the background (the sweep's environment_radiance).
vec3 environment_at(vec3 d) {
    if (E.info.x < 0.5) return P.background.rgb;
    vec3 w = mat3(P.view_to_world) * d;
    float r = E.info.y;
    w = vec3(cos(r) * w.x - sin(r) * w.z, w.y, sin(r) * w.x + cos(r) * w.z);
    return env_bilinear(env_map, env_texel(env_angles(w), textureSize(env_map, 0)));
}

vec3 world_dir(ivec2 p) {
    ivec2 c = clamp(p, ivec2(0), ivec2(P.camera.zw) - 1);
    vec3 v = READ_PIXEL(view_direction, pc.layer, c).xyz;
    vec3 w = mat3(P.view_to_world) * v;
    float r = E.info.y;
    // Rotating the map by r about y = rotating the direction by -r.
    return vec3(cos(r) * w.x - sin(r) * w.z, w.y, sin(r) * w.x + cos(r) * w.z);
}

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(id, ivec2(P.camera.zw)))) return;
    vec4 CA = READ_PIXEL(colour_opacity, pc.layer, id);
    vec3 M = READ_PIXEL(medium, pc.layer, id).rgb;
    vec3 env = P.background.rgb;
    float env_a = P.background.a;
    if (E.info.x > 0.5) {
        vec3 d = world_dir(id);
        vec2 uv = (vec2(id) + 0.5) / P.camera.zw;
        vec3 camera_ray = mat3(P.view_to_world) * normalize(plane_point(uv, 1.0));
        float r = E.info.y;
        camera_ray = vec3(cos(r) * camera_ray.x - sin(r) * camera_ray.z, camera_ray.y,
                          sin(r) * camera_ray.x + cos(r) * camera_ray.z);
        bool bent = dot(normalize(d), camera_ray) < 1.0 - 1e-6;
        if (bent && E.info.z > 0.5) {
            vec3 ds[4] = vec3[4](d, world_dir(id + ivec2(1, 0)), world_dir(id + ivec2(0, 1)),
                                 world_dir(id + ivec2(1, 1)));
            env = env_footprint(env_map, env_sat, E.mean.rgb, ds);
        } else {
            env = env_bilinear(env_map, env_texel(env_angles(d), textureSize(env_map, 0)));
        }
        env_a = 1.0;
    }
    vec3 rgb = CA.rgb + (1.0 - CA.a) * M * env;
    // The first face's reflection sees the volume (sweep_reflect.glsl). Off, the loops'
    // trip counts are zero (llvmpipe runs both sides of a branch, but leaves a loop once
    // every lane is done).
    vec3 face, mirrored, weight;
    float f = first_face((vec2(id) + 0.5) / P.camera.zw, pc.volume_reflections != 0u, face,
                         mirrored, weight);
    if (f > 0.0) {
        vec3 env_seen = environment_at(mirrored);
        vec3 seen = trace_reflected(face, mirrored, env_seen, max(pc.record_stride, 1u));
        rgb += weight * f * (seen - env_seen);
    }
    float a = CA.a + (1.0 - CA.a) * env_a;
    imageStore(frame, id, vec4(rgb, a));
}

#version 460
// Baseline emission-absorption ray marcher (thesis sect. 3.4-3.7, 3.9): perspective rays,
// post-interpolative TF or preintegrated segments, front-to-back compositing (eq. 3.10)
// with opacity correction for the step (eqs. 3.13-3.14), early termination.
// The medium colour (Oddy-Willis, eq. 4.13 without lighting) is carried too, so this is
// exactly the refractive model's compositing when eta is constant.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform Params {
    vec4 cam_pos;      // xyz eye, w = tan(fov_y / 2)
    vec4 cam_forward;  // xyz, w = aspect (width / height)
    vec4 cam_right;
    vec4 cam_up;
    vec4 box_half;     // xyz half extent of the volume box, w = reference step (world units)
    vec4 background;   // linear RGBA composited behind the volume
    vec4 march;        // x = sample distance (reference steps), y = termination alpha,
                       // z = 1 for preintegrated segments, w = unused
    uvec4 size;        // x, y = image size
} P;
layout(set = 0, binding = 1) uniform sampler3D volume;
layout(set = 0, binding = 2) uniform sampler1DArray tf;
layout(set = 0, binding = 3) uniform sampler2DArray preint;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2D frame;

float sample_volume(vec3 p) {
    return texture(volume, p / (2.0 * P.box_half.xyz) + 0.5).r;
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(id, P.size.xy))) return;
    vec2 ndc = (vec2(id) + 0.5) / vec2(P.size.xy) * 2.0 - 1.0;
    vec3 dir = normalize(P.cam_forward.xyz
        + ndc.x * P.cam_pos.w * P.cam_forward.w * P.cam_right.xyz
        - ndc.y * P.cam_pos.w * P.cam_up.xyz);
    vec3 eye = P.cam_pos.xyz;

    // Slab test against the volume box.
    vec3 inv = 1.0 / dir;
    vec3 t0 = (-P.box_half.xyz - eye) * inv;
    vec3 t1 = (P.box_half.xyz - eye) * inv;
    vec3 tmin = min(t0, t1), tmax = max(t0, t1);
    float t_near = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    float t_far = min(min(tmax.x, tmax.y), tmax.z);

    vec3 C = vec3(0.0);
    float A = 0.0;
    vec3 M = vec3(1.0);
    if (t_far > t_near) {
        float ref_step = P.box_half.w;
        float step = P.march.x * ref_step;
        bool preintegrated = P.march.z > 0.5;
        float s_front = sample_volume(eye + t_near * dir);
        float t = t_near;
        while (t < t_far && A < P.march.y) {
            float t_next = min(t + step, t_far);
            float len = t_next - t;
            // The last segment is shorter: correct for its true length so the result does
            // not depend on where the box boundary falls between samples.
            float ratio = len / ref_step;
            float alpha;
            vec3 colour;  // premultiplied, opacity-corrected
            vec3 medium;
            if (preintegrated) {
                float s_back = sample_volume(eye + t_next * dir);
                vec4 ca = texture(preint, vec3(preint_coord(s_front, s_back), 0.0));
                vec3 m = texture(preint, vec3(preint_coord(s_front, s_back), 1.0)).rgb;
                alpha = correct_opacity(ca.a, ratio);
                // eq. 3.14: scale the premultiplied colour with the corrected opacity; for a
                // transparent segment fall back to linear scaling.
                colour = ca.a > 1e-6 ? ca.rgb * (alpha / ca.a) : ca.rgb * ratio;
                medium = correct_medium(m, ratio);
                s_front = s_back;
            } else {
                float s = sample_volume(eye + (0.5 * (t + t_next)) * dir);
                vec4 ca = texture(tf, vec2(tf_coord(s), 0.0));
                vec3 m = texture(tf, vec2(tf_coord(s), 1.0)).rgb;
                alpha = correct_opacity(ca.a, ratio);
                colour = ca.rgb * alpha;
                medium = correct_medium(m, ratio);
            }
            C += (1.0 - A) * M * colour;
            A += (1.0 - A) * alpha;
            M *= medium;
            t = t_next;
        }
    }
    // The background seen through the remaining transmittance and the medium filter.
    vec3 rgb = C + (1.0 - A) * M * P.background.rgb;
    float a = A + (1.0 - A) * P.background.a;
    imageStore(frame, ivec2(id), vec4(rgb, a));
}

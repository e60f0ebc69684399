// The emission-absorption ray march shared by the ray-marched models (ea.comp, ao.comp):
// perspective rays, post-interpolative TF or preintegrated segments, front-to-back
// compositing (eq. 3.10) with opacity correction for the step (eqs. 3.13-3.14), early
// termination. The medium colour (Oddy-Willis, eq. 4.13 without lighting) is carried too,
// so this is exactly the refractive model's compositing when eta is constant.
//
// Before including, declare the Params block P (ea.comp's fields first), the samplers
// volume, tf, preint, and define
//   vec3 sample_shade(vec3 p, vec3 dir)   the light a segment's emission is scaled by,
//                                at its midpoint p (world units) seen along the unit
//                                ray direction dir: 1 for EA, ambient occlusion and
//                                diffuse light for AO, shadowed light through the phase
//                                function for single scattering.
#ifndef REFRAKT_MARCH_GLSL
#define REFRAKT_MARCH_GLSL

float sample_volume(vec3 p) {
    return texture(volume, p / (2.0 * P.box_half.xyz) + 0.5).r;
}

// The premultiplied colour and opacity of the ray through the box, with the background
// composited behind it.
vec4 march_ray(vec3 eye, vec3 dir) {
    float t_near, t_far;
    box_span(eye, dir, P.box_half.xyz, t_near, t_far);
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
            vec3 mid = eye + (0.5 * (t + t_next)) * dir;
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
                float s = sample_volume(mid);
                vec4 ca = texture(tf, vec2(tf_coord(s), 0.0));
                vec3 m = texture(tf, vec2(tf_coord(s), 1.0)).rgb;
                alpha = correct_opacity(ca.a, ratio);
                colour = ca.rgb * alpha;
                medium = correct_medium(m, ratio);
            }
            if (alpha > 0.0) colour *= sample_shade(mid, dir);
            C += (1.0 - A) * M * colour;
            A += (1.0 - A) * alpha;
            M *= medium;
            t = t_next;
        }
    }
    // The background seen through the remaining transmittance and the medium filter.
    vec3 rgb = C + (1.0 - A) * M * P.background.rgb;
    float a = A + (1.0 - A) * P.background.a;
    return vec4(rgb, a);
}

#endif

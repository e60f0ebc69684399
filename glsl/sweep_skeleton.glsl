// Benchmark baseline between the floor and the sweep (`SweepOptions::skeleton`): every
// fetch of the thesis' Algorithm 1 and its plain arithmetic, none of what goes past it.
// Per plane and pixel, as the backward sweep (sweep.frag) makes them:
//   light  — its direction here, the backward step to plane i-1 and the bilinear light
//            colour and direction there (eq. 4.4), value and grad eta here (sample_field,
//            which the `field` lever makes one fetch), the value at the step's origin, the
//            segment's preintegrated opacity and medium (eq. 4.4), the kick (eq. 4.5);
//   view   — its four state reads, value and grad eta at its point, the segment's
//            preintegrated colour, opacity and medium, the bilinear light there, Oddy-Willis
//            compositing (eq. 4.13), the kick (eq. 4.3) and the step to the next plane.
// Not made: the soft-shadow kernel (one light tap instead of three), the intensity law,
// the box-face and sharp-face steps, films, the skin chain, Fresnel reflection, specular,
// clipping, the catch-up of the drawn region. The image is not a rendering (no face is
// refracted as the sweep does); the time is what Algorithm 1 costs on this device before
// the optics the renderer adds, between the floor (moving the state) and the sweep.
// docs/BENCH.md ("Where the goals stand").
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"

#include "sweep_plane_io.glsl"

BACKWARD_STATE_OUTPUTS;
#define STORE_OUTPUTS(at) STORE_BACKWARD_STATE(at)

void PLANE_MAIN() {
    vec2 uv = FRAG_XY / P.camera.zw;
    ivec2 pixel = ivec2(FRAG_XY);
    uint R = pc.read_layer;
    float ds = P.planes.y;
    float ref_step = P.planes.w;

    // ---- light: the backward step (eqs. 4.4, 4.5) ----
    vec3 p = plane_point(uv, pc.depth);
    vec3 ld_here = READ_PIXEL(light_direction, R, pixel).xyz;
    vec3 lp = p - ld_here * (ds / ld_here.z);
    vec2 uv_lp = project(lp);
    vec3 light_prev = READ_BUFFER(light_colour, R, uv_lp).rgb;
    vec3 dir_prev = READ_BUFFER(light_direction, R, uv_lp).xyz;
    float f_p;
    vec3 grad_p;
    sample_field(p, f_p, grad_p);
    float f_lp = value_at_tex(to_tex(lp));
    vec3 seg_c, seg_m;
    float seg_a;
    segment(f_lp, f_p, length(p - lp) / ref_step, false, seg_c, seg_a, seg_m);
    vec3 light = light_prev * (1.0 - seg_a) * seg_m;
    vec3 light_dir = limit_direction(dir_prev + length(p - lp) * grad_p);

    // ---- viewing ray (eqs. 4.3, 4.13) ----
    vec2 vp_xy = READ_VIEW_XY(R, pixel);
    vec4 vd4 = READ_PIXEL(view_direction, R, pixel);   // v, the value at the point
    vec4 CA = READ_PIXEL(colour_opacity, R, pixel);
    vec4 M4 = READ_PIXEL(medium, R, pixel);
    vec3 vp = vec3(vp_xy, pc.depth);
    float f_v;
    vec3 grad_v;
    sample_field(vp, f_v, grad_v);
    vec3 d = normalize(vd4.xyz);
    vec3 c, m;
    float a;
    segment(vd4.w, f_v, ds / (d.z * ref_step), false, c, a, m);
    vec3 i_d = READ_BUFFER(light_colour, R, project(vp)).rgb;
    vec3 C = CA.rgb + (1.0 - CA.a) * M4.rgb * c * i_d;   // eq. 4.13
    float A = CA.a + (1.0 - CA.a) * a;
    vec3 vd = limit_direction(vd4.xyz + (ds / d.z) * grad_v);
    vec3 dn = normalize(vd);

    out_light_colour = vec4(light, 0.0);
    out_light_direction = vec4(light_dir, 0.0);
    WRITE_VIEW_XY((vp + dn * (ds / dn.z)).xy);
    out_view_direction = vec4(vd, f_v);
    out_colour_opacity = vec4(C, A);
    out_medium = vec4(M4.rgb * m, M4.w);
}

COMPUTE_ENTRY

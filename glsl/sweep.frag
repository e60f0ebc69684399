#version 460
// One plane of the refractive plane sweep (thesis ch. 4, Algorithm 1): a full-screen draw
// per plane; reads the previous plane's state from layer `read_layer` and writes this
// plane's into the other layer (the render pass's attachments).
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;   // depth of this plane
    uint pad;
} pc;

layout(location = 0) out vec4 out_light_colour;
layout(location = 1) out vec4 out_light_direction;
layout(location = 2) out vec4 out_view_position;
layout(location = 3) out vec4 out_view_direction;
layout(location = 4) out vec4 out_colour_opacity;
layout(location = 5) out vec4 out_medium;

const float PI = 3.14159265358979;

// Light colour and direction at `uv` of the read layer, bilinearly interpolated with the
// directions weighted by the light they carry: where lit and fully absorbed rays meet (a
// shadow edge, a stopped-down aperture, rays crossing in a caustic), the direction of light
// that is not there must not bend the light that is. Where no light arrives at all, plain
// bilinear weights keep the direction field defined.
void light_at(vec2 uv, uint layer, out vec3 light, out vec3 dir) {
    ivec2 size = textureSize(light_colour_0, 0);
    vec2 x = uv * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 t = x - vec2(i);
    ivec2 hi = size - 1;
    light = vec3(0.0);
    vec3 d_plain = vec3(0.0);
    vec3 d_lit = vec3(0.0);
    float lit = 0.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 c = clamp(i + o, ivec2(0), hi);
        float w = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
        vec3 l = READ_PIXEL(light_colour, layer, c).rgb;
        vec3 d = READ_PIXEL(light_direction, layer, c).xyz;
        float lum = dot(l, vec3(0.2126, 0.7152, 0.0722));
        light += w * l;
        d_plain += w * d;
        d_lit += w * lum * d;
        lit += w * lum;
    }
    dir = lit > 1e-6 ? d_lit / lit : d_plain;
}

float hash(uvec3 v) {
    uint h = v.x * 0x8da6b343u ^ v.y * 0xd8163841u ^ v.z * 0xcb1ab31fu;
    h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
    return float(h & 0xffffu) / 65536.0;
}

// Preintegrated segment from value a to value b, `ratio` reference steps long:
// premultiplied colour, opacity (eq. 3.19), medium (power rule).
void segment(float a, float b, float ratio, bool clip, out vec3 colour, out float alpha,
             out vec3 m) {
    vec2 c = preint_coord(a, b);
    vec4 ca = textureLod(preint, vec3(c, 0.0), 0.0);
    m = correct_medium(textureLod(preint, vec3(c, 1.0), 0.0).rgb, ratio);
    alpha = correct_opacity(ca.a, ratio);
    colour = ca.a > 1e-6 ? ca.rgb * (alpha / ca.a) : ca.rgb * ratio;
    if (clip) { alpha = 0.0; colour = vec3(0.0); }  // clipping keeps the medium (Fig. 6.6)
}

// Cook-Torrance Fresnel for unpolarised light (eq. 4.12; the thesis prints the bracket's
// square and (g+c) as (g+2) wrongly). eta_ratio = eta_t / eta_i; total reflection where g
// would be imaginary.
float fresnel(float c, float eta_ratio) {
    float g2 = eta_ratio * eta_ratio - 1.0 + c * c;
    if (g2 <= 0.0) return 1.0;
    float g = sqrt(g2);
    float a = (g - c) / (g + c);
    float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

// Cook-Torrance specular (eqs. 4.9-4.11): GGX D with alpha = roughness^2, Smith-Schlick G
// with k = (roughness + 1)^2 / 8. Returns the reflected fraction of the incident light
// (R_s times n.l).
float specular_term(vec3 n, vec3 l, vec3 v, float eta_ratio) {
    float nl = dot(n, l), nv = dot(n, v);
    if (nl <= 0.0 || nv <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float nh = max(dot(n, h), 0.0);
    float r = P.specular.x;
    float a2 = r * r * r * r;
    float den = nh * nh * (a2 - 1.0) + 1.0;
    float D = a2 / (PI * den * den);
    float k = (r + 1.0) * (r + 1.0) / 8.0;
    float G = (nl / (nl * (1.0 - k) + k)) * (nv / (nv * (1.0 - k) + k));
    float F = fresnel(max(dot(v, h), 0.0), eta_ratio);
    return D * F * G / (4.0 * nv);
}

void main() {
    vec2 size = P.camera.zw;
    vec2 uv = gl_FragCoord.xy / size;
    uint R = pc.read_layer;
    float ds = P.planes.y;
    float ref_step = P.planes.w;

    // ---- light propagation (sect. 4.2, 5.2) -------------------------------------------
    vec3 p = plane_point(uv, pc.depth);
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec3 ld_here = READ_PIXEL(light_direction, R, pixel).xyz;
    // Backward (semi-Lagrangian) step: follow the light direction back to plane i-1.
    vec3 lp = p - ld_here * (ds / ld_here.z);
    vec2 uv_lp = project(lp);

    // Elliptical 3-tap kernel (after Patel et al.): a disc of radius `softness` reference
    // steps perpendicular to the light, projected onto the previous plane (stretched along
    // the light's lateral direction), with a per-pixel, per-plane random rotation. Applied
    // at every plane, the blur accumulates (incremental convolution): penumbrae widen with
    // distance behind the occluder and with softness.
    vec3 light_prev = vec3(0.0);
    vec3 dir_prev = vec3(0.0);
    float softness = P.light_dir.w;
    if (softness > 0.0) {
        vec3 dn = normalize(ld_here);
        float radius = softness * ref_step;                          // world units
        vec2 lateral = length(dn.xy) > 1e-6 ? normalize(dn.xy) : vec2(1.0, 0.0);
        vec2 across = vec2(-lateral.y, lateral.x);
        float world_per_uv_y = 2.0 * (pc.depth - ds) * P.camera.x;  // plane i-1 height
        vec2 to_uv = vec2(1.0 / (world_per_uv_y * P.camera.y), -1.0 / world_per_uv_y);
        float rot = 2.0 * PI * hash(uvec3(gl_FragCoord.xy, pc.plane));
        for (int k = 0; k < 3; ++k) {
            float phi = rot + float(k) * (2.0 * PI / 3.0);
            vec2 offset = radius * (cos(phi) / dn.z * lateral + sin(phi) * across);
            vec3 l, d;
            light_at(uv_lp + offset * to_uv, R, l, d);
            light_prev += l;
            dir_prev += d;
        }
        light_prev /= 3.0;
        dir_prev /= 3.0;
    } else {
        light_at(uv_lp, R, light_prev, dir_prev);
    }

    // Intensity law (eqs. 4.6-4.8): I = S_{i-1} / S_i, the areas of this pixel's footprint
    // on this plane and of the light's origin on the previous one. Areas from the cross
    // product of the screen-space derivatives (exact for sheared footprints).
    float s_here = length(cross(dFdxFine(p), dFdyFine(p)));
    float s_prev = length(cross(dFdxFine(lp), dFdyFine(lp)));
    float gain = s_prev / s_here;
    // Chapter 7's bright spots: neighbours with very different directions give huge
    // footprints. Bound the gain per plane (P.light_colour.w) and never let NaN/Inf through.
    if (!(gain >= 0.0) || isinf(gain)) gain = 1.0;
    gain = min(gain, P.light_colour.w);

    float f_p, f_lp;
    vec3 grad_f_p, grad_eta_p;
    sample_field(p, f_p, grad_f_p, grad_eta_p);
    f_lp = value_at_tex(to_tex(lp));
    float light_len = length(p - lp);
    vec3 seg_c; float seg_a; vec3 seg_m;
    segment(f_lp, f_p, light_len / ref_step, clipped(p), seg_c, seg_a, seg_m);
    vec3 light = light_prev * gain * (1.0 - seg_a) * seg_m;               // eq. 4.4
    vec3 light_dir = limit_direction(dir_prev + light_len * grad_eta_p);   // eq. 4.5
    if (any(isnan(light)) || any(isinf(light))) light = vec3(0.0);

    // ---- viewing rays (sect. 4.3, 5.2) ------------------------------------------------
    vec4 vp4 = READ_PIXEL(view_position, R, pixel);
    vec4 vd4 = READ_PIXEL(view_direction, R, pixel);
    vec4 CA = READ_PIXEL(colour_opacity, R, pixel);
    vec4 M4 = READ_PIXEL(medium, R, pixel);
    vec3 vp = vp4.xyz;
    vec3 vd = vd4.xyz;
    vec3 C = CA.rgb;
    float A = CA.a;
    vec3 M = M4.rgb;

    float f_v;
    vec3 grad_f, grad_eta;
    sample_field(vp, f_v, grad_f, grad_eta);
    float eta_here = eta_of(f_v);
    vec3 dir = normalize(vd);
    float seg_len = ds / dir.z;   // arc length from plane i-1 to this plane

    if (A < P.specular.z) {
        vec2 uv_v = project(vp);
        vec3 i_d = READ_BUFFER(light_colour, R, uv_v).rgb;
        vec3 i_s = vec3(0.0);
        bool unlit = P.volume_dims.w > 0.5;
        if (unlit) {
            i_d = vec3(1.0);
        } else if (P.specular.y > 0.0 && dot(grad_f, grad_f) > 1e-8) {
            vec3 l = -normalize(READ_BUFFER(light_direction, R, uv_v).xyz);
            vec3 v = -dir;
            vec3 n = normalize(grad_f);
            if (dot(n, v) < 0.0) n = -n;
            i_s = P.specular.y * specular_term(n, l, v, eta_here / vd4.w) * i_d;
        }
        vec3 c; float a; vec3 m;
        segment(vp4.w, f_v, seg_len / ref_step, clipped(vp), c, a, m);
        // Oddy-Willis compositing (eq. 4.13): the medium factor once, specular not
        // multiplied by opacity.
        C += (1.0 - A) * M * (c * i_d + i_s);
        A += (1.0 - A) * a;
        M *= m;
    }
    // Bend (eq. 4.3) and advance to the next plane.
    vd = limit_direction(vd + seg_len * grad_eta);
    vec3 next_dir = normalize(vd);
    vec3 vp_next = vp + next_dir * (ds / next_dir.z);

    out_light_colour = vec4(light, 0.0);
    out_light_direction = vec4(light_dir, 0.0);
    out_view_position = vec4(vp_next, f_v);
    out_view_direction = vec4(vd, eta_here);
    out_colour_opacity = vec4(C, A);
    out_medium = vec4(M, 0.0);
}

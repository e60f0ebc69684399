// Environment lookups for the composite (thesis sect. 4.4, 5.3). Conventions match
// src/environment.rs: longitude phi = atan2(d.x, -d.z) in [-pi, pi) left to right, latitude
// theta = asin(d.y), +pi/2 (zenith) in the top row.
#ifndef REFRAKT_ENVIRONMENT_GLSL
#define REFRAKT_ENVIRONMENT_GLSL

const float ENV_PI = 3.14159265358979;

vec2 env_angles(vec3 d) {
    d = normalize(d);
    return vec2(atan(d.x, -d.z), asin(clamp(d.y, -1.0, 1.0)));
}

// Continuous texel coordinates of (phi, theta).
vec2 env_texel(vec2 a, ivec2 size) {
    return vec2((a.x + ENV_PI) / (2.0 * ENV_PI) * float(size.x),
                (0.5 * ENV_PI - a.y) / ENV_PI * float(size.y));
}

// Bilinear lookup, wrapping across the seam, clamping at the poles (f32 weights).
vec3 env_bilinear(sampler2D map, vec2 t) {
    ivec2 size = textureSize(map, 0);
    vec2 x = t - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 f = x - vec2(i);
    vec3 c[4];
    for (int k = 0; k < 4; ++k) {
        ivec2 o = i + ivec2(k & 1, k >> 1);
        o.x = ((o.x % size.x) + size.x) % size.x;
        o.y = clamp(o.y, 0, size.y - 1);
        c[k] = texelFetch(map, o, 0).rgb;
    }
    return mix(mix(c[0], c[1], f.x), mix(c[2], c[3], f.x), f.y);
}

// S over [0, x) x [0, y) (zero on the empty edges).
vec3 sat_at(sampler2D sat, int x, int y) {
    if (x <= 0 || y <= 0) return vec3(0.0);
    return texelFetch(sat, ivec2(x - 1, y - 1), 0).rgb;
}

vec3 sat_sum(sampler2D sat, int x0, int x1, int y0, int y1) {
    return sat_at(sat, x1, y1) - sat_at(sat, x0, y1) - sat_at(sat, x1, y0) + sat_at(sat, x0, y0);
}

// Mean of the map over the texel box [x0, x1) x [y0, y1); x0 > x1 wraps across the seam.
vec3 sat_average(sampler2D sat, vec3 mean, int x0, int x1, int y0, int y1) {
    ivec2 size = textureSize(sat, 0);
    float rows = float(y1 - y0);
    if (x0 <= x1) {
        return sat_sum(sat, x0, x1, y0, y1) / (float(x1 - x0) * rows) + mean;
    }
    vec3 s = sat_sum(sat, x0, size.x, y0, y1) + sat_sum(sat, 0, x1, y0, y1);
    return s / (float(size.x - x0 + x1) * rows) + mean;
}

// Average of the map over the (longitude, latitude) rectangle spanned by four directions.
// Longitudes are unwrapped around the first so a footprint straddling the seam stays
// small; one that contains a pole, or spans more than half the sphere, takes the full
// longitude range. Footprints of a texel or less are read bilinearly (the f32 table's
// corner differences are least accurate for tiny boxes).
vec3 env_footprint(sampler2D map, sampler2D sat, vec3 mean, vec3 d[4]) {
    ivec2 size = textureSize(map, 0);
    vec2 a0 = env_angles(d[0]);
    float lo = a0.x, hi = a0.x, tlo = a0.y, thi = a0.y;
    for (int k = 1; k < 4; ++k) {
        vec2 a = env_angles(d[k]);
        float phi = a.x;
        if (phi - a0.x > ENV_PI) phi -= 2.0 * ENV_PI;
        if (phi - a0.x < -ENV_PI) phi += 2.0 * ENV_PI;
        lo = min(lo, phi); hi = max(hi, phi);
        tlo = min(tlo, a.y); thi = max(thi, a.y);
    }
    vec2 t_lo = env_texel(vec2(lo, thi), size);
    vec2 t_hi = env_texel(vec2(hi, tlo), size);
    bool full = (hi - lo) > ENV_PI || thi > 0.5 * ENV_PI - 1e-3 || tlo < -0.5 * ENV_PI + 1e-3;
    if (!full && t_hi.x - t_lo.x <= 1.0 && t_hi.y - t_lo.y <= 1.0) {
        return env_bilinear(map, 0.5 * (t_lo + t_hi));
    }
    int y0 = clamp(int(floor(t_lo.y)), 0, size.y - 1);
    int y1 = clamp(int(ceil(t_hi.y)), y0 + 1, size.y);
    if (full) return sat_average(sat, mean, 0, size.x, y0, y1);
    int x0 = int(floor(t_lo.x));
    int x1 = int(ceil(t_hi.x));
    if (x1 <= x0) x1 = x0 + 1;
    x0 = ((x0 % size.x) + size.x) % size.x;
    x1 = ((x1 % size.x) + size.x) % size.x;
    if (x1 == 0) x1 = size.x;
    return sat_average(sat, mean, x0, x1, y0, y1);
}

#endif

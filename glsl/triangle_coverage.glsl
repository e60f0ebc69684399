// The exact coverage of a pixel by a triangle, with weights linear between its corners:
// the cells deposit of the sweep's light splat (light_splat_ray.glsl) and the eikonal
// light simulator's receiver planes (light_wavefront_step.comp) spread flux over the
// area a wavefront's cell or patch spans on a plane with it.
#ifndef REFRAKT_TRIANGLE_COVERAGE_GLSL
#define REFRAKT_TRIANGLE_COVERAGE_GLSL

// Along the edge a -> b, clipped to the pixel whose lower corner is `lo` (x in [lo.x,
// lo.x + 1]), with c = clamp(y - lo.y, 0, 1): the integrals of c, x c and c² / 2 over x.
// Summed
// over a closed polygon's edges they are minus the area, the x moment and the y moment of
// the polygon's part inside the pixel (Green's theorem: with P(x, y) = C(y), the integral
// of P dx around the outline is minus the integral of dC/dy over the area, and
// clamping y and x keeps exactly the part inside the pixel). c is 0, y or 1 on at most
// three pieces of the edge, split where y crosses 0 and 1; on each piece the integrands
// are polynomials of degree at most 2 in x, which Simpson's rule integrates exactly.
vec3 edge_moments(vec2 a, vec2 b, vec2 lo) {
    a.y -= lo.y;
    b.y -= lo.y;
    float xa = clamp(a.x, lo.x, lo.x + 1.0), xb = clamp(b.x, lo.x, lo.x + 1.0);
    float dx = b.x - a.x;
    float inv = dx != 0.0 ? 1.0 / dx : 0.0;
    float ya = a.y + clamp((xa - a.x) * inv, 0.0, 1.0) * (b.y - a.y);
    float yb = a.y + clamp((xb - a.x) * inv, 0.0, 1.0) * (b.y - a.y);
    float ex = xb - xa, ey = yb - ya;
    float iy = ey != 0.0 ? 1.0 / ey : 0.0;
    float t0 = clamp(-ya * iy, 0.0, 1.0), t1 = clamp((1.0 - ya) * iy, 0.0, 1.0);
    float cuts[4] = float[4](0.0, min(t0, t1), max(t0, t1), 1.0);
    vec3 sum = vec3(0.0);
    for (int k = 0; k < 3; ++k) {
        float s = cuts[k], e = cuts[k + 1];
        vec3 acc = vec3(0.0);
        for (int q = 0; q < 3; ++q) {
            float t = q == 0 ? s : (q == 1 ? 0.5 * (s + e) : e);
            float wq = q == 1 ? 4.0 : 1.0;
            float x = xa + t * ex;
            float c = clamp(ya + t * ey, 0.0, 1.0);
            acc += wq * vec3(c, x * c, 0.5 * c * c);
        }
        sum += (e - s) / 6.0 * acc;
    }
    return sum * ex;
}

float cross2(vec2 u, vec2 v) { return u.x * v.y - u.y * v.x; }

// For triangle (a, b, c) and pixel `p` (integer corner): the integral over the pixel's
// part of the triangle of each corner's barycentric weight, divided by the triangle's
// area (each in [0, 1/3]; over all pixels they sum to 1/3). Flux spread over the triangle
// with a density linear between its corners, f_v / (2 area) at corner v, puts
// sum_v (f_v / 2) * w_v in the pixel: the irradiance interpolates the corners' as a
// wavefront does, and the triangle's flux (f_a + f_b + f_c) / 6 is conserved exactly.
// Either orientation (a folded cell's triangles turn over). A triangle below 1e-5 px² of
// area (a perfect focus) counts as the point at its centre.
vec3 triangle_weights(vec2 a, vec2 b, vec2 c, vec2 p) {
    // Coordinates relative to the triangle's centre: its corners and moments are then as
    // small as the triangle, and the weights below lose no digits to cancellation
    // (relative to the pixel's corner they lost 1e-7 / area: 1.7e-4 of a frame between
    // the fragment and the compute splat, measured).
    vec2 g = (a + b + c) / 3.0;
    a -= g;
    b -= g;
    c -= g;
    vec2 lo = p - g;
    float a2 = cross2(b - a, c - a);   // twice the signed area
    vec3 m = -(edge_moments(a, b, lo) + edge_moments(b, c, lo) + edge_moments(c, a, lo));
    m.z += lo.y * m.x;   // the y moment about the centre
    // The integral of lambda_v = cross(w - x, u - x) / a2 (w, u the other corners) over
    // the part: cross(w, u) area + x moment (w.y - u.y) - y moment (w.x - u.x).
    vec3 lambda = vec3(cross2(b, c) * m.x + m.y * (b.y - c.y) - m.z * (b.x - c.x),
                       cross2(c, a) * m.x + m.y * (c.y - a.y) - m.z * (c.x - a.x),
                       cross2(a, b) * m.x + m.y * (a.y - b.y) - m.z * (a.x - b.x));
    vec3 w = clamp(lambda / (0.5 * a2 * a2), vec3(0.0), vec3(1.0 / 3.0));
    bool inside = all(lessThanEqual(lo, vec2(0.0))) && all(greaterThan(lo + 1.0, vec2(0.0)));
    return abs(0.5 * a2) > 1e-5 ? w : vec3(inside ? 1.0 / 3.0 : 0.0);
}

#endif

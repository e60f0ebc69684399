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
// three pieces of the edge, split where y crosses 0 and 1; on each piece c and x are
// linear, so the integrals are closed forms in the piece's end values (for linear u, w
// over a piece of length L: the integral of u is L (u0 + u1) / 2, of u w is
// L (2 u0 w0 + u0 w1 + u1 w0 + 2 u1 w1) / 6), which the pieces' four ends share. (Simpson's
// rule, exact too, took three points a piece: nine evaluations where these take four;
// docs/NOTES.md, "Light as a wavefront".)
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
    // The pieces' ends: 0, the two crossings in order, 1.
    vec4 t = vec4(0.0, min(t0, t1), max(t0, t1), 1.0);
    vec4 x = xa + t * ex;
    vec4 c = clamp(ya + t * ey, 0.0, 1.0);
    vec3 piece_len = t.yzw - t.xyz;
    vec3 c0 = c.xyz, c1 = c.yzw, x0 = x.xyz, x1 = x.yzw;
    float area = dot(piece_len, c0 + c1) * 0.5;
    float mx = dot(piece_len, 2.0 * x0 * c0 + x0 * c1 + x1 * c0 + 2.0 * x1 * c1) / 6.0;
    float my = dot(piece_len, c0 * c0 + c0 * c1 + c1 * c1) / 6.0;
    return vec3(area, mx, my) * ex;
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

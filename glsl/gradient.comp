#version 460
// The smoothed gradient volume: the gradient of the scalar value convolved with a 3D
// Gaussian (derivative-of-Gaussian filters, sigma in voxels), per voxel, in value units
// per voxel. It gives the orientation of surfaces, and of faces of glass, for the viewing
// rays' Snell steps, Fresnel reflections, highlights and the shading's layer model (the
// thesis' central differences one voxel apart tilt a sharp face's normal towards the grid
// axes; src/render/gradient.rs has the measured figures). It depends on the volume only,
// not on the transfer functions: the gradient of eta = eta_tf(value) is parallel to it.
//
// Separable, in three dispatches (push constant `axis`), each convolving along one axis
// with both the Gaussian G and its derivative D, fetching each tap once:
//   axis 0: f              -> (D_x f, G_x f)
//   axis 1: (a, b)         -> (G_y a, D_y b, G_y b)             a = D_x f, b = G_x f
//   axis 2: (p, q, s)      -> (G_z p, G_z q, D_z s, G_z s)
// leaving (df/dx, df/dy, df/dz, smoothed f). Outside the volume the value is zero, as the
// sweep samples it (glsl/sweep_common.glsl value_at_tex): matter that reaches the box's
// side has a face there.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler3D src;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image3D dst;

layout(push_constant) uniform Push {
    int axis;
    float sigma;    // voxels
    int radius;     // taps either side (ceil(3 sigma))
} pc;

void main() {
    ivec3 dims = imageSize(dst);
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, dims))) return;
    ivec3 e = ivec3(0);
    e[pc.axis] = 1;
    // Weights normalised so that G sums to 1 and D differentiates a linear ramp exactly
    // (sum of k D_k = 1): truncation at 3 sigma neither scales the value nor the slope.
    vec4 g = vec4(0.0), d = vec4(0.0);
    float gsum = 0.0, dsum = 0.0;
    float inv2s2 = 0.5 / (pc.sigma * pc.sigma);
    for (int k = -pc.radius; k <= pc.radius; ++k) {
        float kk = float(k);
        float wg = exp(-kk * kk * inv2s2);
        float wd = kk * wg;
        gsum += wg;
        dsum += kk * wd;
        ivec3 q = p + k * e;
        vec4 v = vec4(0.0);
        if (all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, dims))) {
            v = texelFetch(src, q, 0);
        }
        g += wg * v;
        d += wd * v;
    }
    g /= gsum;
    d /= dsum;
    vec4 outv;
    if (pc.axis == 0) {
        outv = vec4(d.x, g.x, 0.0, 0.0);
    } else if (pc.axis == 1) {
        outv = vec4(g.x, d.y, g.y, 0.0);
    } else {
        outv = vec4(g.x, g.y, d.z, g.z);
    }
    imageStore(dst, p, outv);
}

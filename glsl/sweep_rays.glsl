// The forward transport's light rays: one per texel of two 2-layer image arrays (ping-pong
// like the state), independent of the screen's size. Ray r = j * columns + i of the grid
// (i, j) lives at texel (r % image width, r / image width), so a grid of any shape up to
// the images' texel count fits without reallocating.
#ifndef REFRAKT_SWEEP_RAYS_GLSL
#define REFRAKT_SWEEP_RAYS_GLSL

// rgb = flux, a = view x on the ray's plane.
STATE_IMAGE(13, rays_flux);
// xyz = v = eta dx/ds, w = view y on the ray's plane.
STATE_IMAGE(14, rays_direction);

ivec2 ray_grid() { return ivec2(P.light_rays.xy); }

ivec2 ray_texel(int r) {
    int w = int(P.light_rays.z);
    return ivec2(r % w, r / w);
}

int ray_index(ivec2 ij) { return ij.y * int(P.light_rays.x) + ij.x; }

bool ray_exists(ivec2 ij) {
    return all(greaterThanEqual(ij, ivec2(0))) && all(lessThan(ij, ray_grid()));
}

#define READ_RAY(name, layer, r) FETCH_LAYER(name, ray_texel(r), layer)

// The compute splat's per-ray dispatches (deposits, bin lists, the scatter of blocks)
// cover the grid rows the plane deposits, pc.extent.y of them from row pc.origin.y (the
// `rays` lever, render/refract/ray_rows.rs: rows not needed yet hold launch states, and
// deposit nothing); an invocation past them deposits nothing. For the includers that
// declare the compute sweep's push block.
#define DEPOSITED_RAY (ivec2(gl_GlobalInvocationID.xy) + ivec2(0, pc.origin.y))
#define DEPOSITS_HERE(ij) (ray_exists(ij) && (ij).y < pc.origin.y + pc.extent.y)

#endif

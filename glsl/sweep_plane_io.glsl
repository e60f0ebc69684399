// What a plane shader of the sweep reads and writes besides the state images: its push
// constants, its pixel, and its outputs, for both paths. Included after
// sweep_buffers.glsl by the plane shaders (sweep_plane.glsl, sweep_floor.glsl,
// sweep_skeleton.glsl), which name their outputs with PLANE_OUTPUT and their entry point
// PLANE_MAIN.
//
// Fragment path (SWEEP_COMPUTE 0): one full-screen draw per plane inside a render pass;
// the pixel is gl_FragCoord, the outputs are colour attachments (the write layer's views).
// Compute path (SWEEP_COMPUTE 1, issue 31): one dispatch per plane over the pixels the
// plane shades (an origin and extent pushed per plane, 8 x 8 invocations a workgroup);
// the outputs are stored into the write layer, 1 - read_layer, of the same images.
// On Hopper GPUs only 4 of 132 SMs run fragment shaders; dispatches use all of them.
#ifndef REFRAKT_SWEEP_PLANE_IO_GLSL
#define REFRAKT_SWEEP_PLANE_IO_GLSL

#if SWEEP_COMPUTE
layout(local_size_x = 8, local_size_y = 8) in;
// Mirrored by render::refract::ComputePush (36 bytes, every pipeline of the compute sweep,
// so that switching between them keeps the descriptor set bound).
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;     // depth of this plane
    float unit;      // the splat's fixed-point unit (light_splat_main.glsl, sweep_resolve.comp)
    ivec2 origin;    // first pixel (or ray texel) of the dispatch
    ivec2 extent;    // pixels (or ray texels) it covers
    uint pad;        // the light rays' pass: the previous plane's moved texel rows
} pc;
ivec2 g_pixel;
bool g_keep_layer = false;   // SKIP_PLANE: store nothing, the write layer stays as it is
#define FRAG_XY (vec2(g_pixel) + 0.5)
#define SKIP_PLANE { g_keep_layer = true; return; }
#define PLANE_OUTPUT(loc, name) vec4 name
#define PLANE_MAIN plane_main
#else
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;   // depth of this plane
    uint pad;
    vec2 region[8];   // the polygon the plane's draw covers (sweep_region.vert)
} pc;
#define FRAG_XY gl_FragCoord.xy
// The render pass loads the write layer: a discarded pixel keeps what it holds.
#define SKIP_PLANE discard
#define PLANE_OUTPUT(loc, name) layout(location = loc) out vec4 name
#define PLANE_MAIN main
#endif

// The backward transport's state: five images, 20 scalars for Algorithm 1's 19 and the
// skin chain (issue 31's compact state; it was six images, 24 slots, until 2026-12-07):
//   light_colour     light colour (rgb), the viewing ray's point x on its plane (w)
//   light_direction  light direction v = eta dx/ds (xyz), the viewing ray's point y (w)
//   view_direction   the viewing ray's v (xyz), the value at its point (w)
//   colour_opacity   composited colour and opacity (eq. 4.13)
//   medium           medium colour product (rgb), the skin chain or a mark (w)
// The viewing ray's depth is its plane's (pc.depth: every step ends on the next plane),
// and eta at its point is eta_of(the value there), so neither is stored. The forward
// transport keeps the point's x, y in view_position (its light is in the rays' images).
// A shader that writes the whole backward state (the backward sweep, the floor, the
// skeleton) declares `BACKWARD_STATE_OUTPUTS;` and defines STORE_OUTPUTS(at) as
// STORE_BACKWARD_STATE(at); the fragment path's render pass has these five attachments
// in this order. (medium.w's mark of a ray still on plane 0: VIEW_RAY_AT_SETUP,
// sweep_common.glsl.)
#define BACKWARD_STATE_OUTPUTS \
    PLANE_OUTPUT(0, out_light_colour); \
    PLANE_OUTPUT(1, out_light_direction); \
    PLANE_OUTPUT(2, out_view_direction); \
    PLANE_OUTPUT(3, out_colour_opacity); \
    PLANE_OUTPUT(4, out_medium)
#define STORE_BACKWARD_STATE(at) \
    imageStore(light_colour, at, out_light_colour); \
    imageStore(light_direction, at, out_light_direction); \
    imageStore(view_direction, at, out_view_direction); \
    imageStore(colour_opacity, at, out_colour_opacity); \
    imageStore(medium, at, out_medium);

// The viewing ray's point x, y on its plane: read from texel `px` of layer R, and
// written into this plane's outputs (their other components set first).
#if FORWARD_LIGHT
#define READ_VIEW_XY(R, px) READ_PIXEL(view_position, R, px).xy
#define WRITE_VIEW_XY(xy) out_view_position = vec4((xy), 0.0, 0.0)
#else
#define READ_VIEW_XY(R, px) \
    vec2(READ_LIGHT_PIXEL(light_colour, 0u, R, px).w, \
         READ_LIGHT_PIXEL(light_direction, 1u, R, px).w)
#define WRITE_VIEW_XY(xy) { out_light_colour.w = (xy).x; out_light_direction.w = (xy).y; }
#endif

#if SWEEP_COMPUTE && LIGHT_TILE_READS
// The `tile` lever (issue 31, specialization constants 12 and 13): the backward plane's
// light reads served from a workgroup tile. A pixel's reads of the previous plane's
// light fall near it: the backward step's origin (a plane spacing along the light), the
// soft kernel's three taps around it, the neighbours' origins for the intensity law, the
// viewing ray's light where it is. So each workgroup first loads the light colour and
// direction of its 8 x 8 pixels and LIGHT_TILE_HALO pixels around them into shared
// memory, (8 + 2 halo)^2 texels of each, a few per invocation, and every read that falls
// inside is served from there; one that falls outside (light turned far, an image edge
// clamped away from the tile) is fetched as before. The tile holds the very texels the
// fetches would return, and the bilinear arithmetic is the same, so the image is the
// same bit for bit (tests/compute_sweep.rs, halo 4 and halo 0, where every read beyond
// the workgroup's own pixels is a fetch). For GPUs: on llvmpipe fetches and shared
// reads cost much the same (docs/NOTES.md, "The light's tile").
layout(constant_id = 12) const bool LIGHT_TILE = false;
layout(constant_id = 13) const int LIGHT_TILE_HALO = 4;
const int LIGHT_TILE_SIDE = 8 + 2 * LIGHT_TILE_HALO;
shared vec4 tile_light_colour[LIGHT_TILE_SIDE * LIGHT_TILE_SIDE];
shared vec4 tile_light_direction[LIGHT_TILE_SIDE * LIGHT_TILE_SIDE];
ivec2 g_tile_origin;   // the image texel of the tile's first entry

// Every invocation of the workgroup, in uniform control flow (before any returns).
// Texels past the image's edge are loaded clamped onto it; a read never asks for one
// there (its taps are clamped first), so they are never served.
void load_light_tile() {
    g_tile_origin = pc.origin + ivec2(gl_WorkGroupID.xy) * 8 - LIGHT_TILE_HALO;
    ivec2 hi = imageSize(light_colour).xy - 1;
    const int n = LIGHT_TILE_SIDE * LIGHT_TILE_SIDE;
    for (int k = int(gl_LocalInvocationIndex); k < n; k += 64) {
        ivec2 t = g_tile_origin + ivec2(k % LIGHT_TILE_SIDE, k / LIGHT_TILE_SIDE);
        ivec3 at = ivec3(clamp(t, ivec2(0), hi), pc.read_layer);
        tile_light_colour[k] = imageLoad(light_colour, at);
        tile_light_direction[k] = imageLoad(light_direction, at);
    }
    memoryBarrierShared();
    barrier();
}

vec4 light_tile_texel(uint which, ivec2 texel, uint layer) {
    ivec2 t = texel - g_tile_origin;
    if (LIGHT_TILE && layer == pc.read_layer && all(greaterThanEqual(t, ivec2(0)))
        && all(lessThan(t, ivec2(LIGHT_TILE_SIDE)))) {
        int k = t.y * LIGHT_TILE_SIDE + t.x;
        return which == 0u ? tile_light_colour[k] : tile_light_direction[k];
    }
    ivec3 at = ivec3(texel, layer);
    return which == 0u ? imageLoad(light_colour, at) : imageLoad(light_direction, at);
}
#define LOAD_LIGHT_TILE if (LIGHT_TILE) load_light_tile();
#else
#define LOAD_LIGHT_TILE
#endif

// The compute entry point: the invocation's pixel, the plane's work, its stores
// (STORE_OUTPUTS, which the including shader defines from its outputs).
#if SWEEP_COMPUTE
#define COMPUTE_ENTRY \
    void main() { \
        LOAD_LIGHT_TILE \
        ivec2 gid = ivec2(gl_GlobalInvocationID.xy); \
        if (any(greaterThanEqual(gid, pc.extent))) return; \
        g_pixel = pc.origin + gid; \
        plane_main(); \
        if (g_keep_layer) return; \
        ivec3 at = ivec3(g_pixel, 1u - pc.read_layer); \
        STORE_OUTPUTS(at) \
    }
#else
#define COMPUTE_ENTRY
#endif

#endif

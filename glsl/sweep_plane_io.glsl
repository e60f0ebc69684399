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
// Mirrored by render::refract::ComputePush (32 bytes, every pipeline of the compute sweep,
// so that switching between them keeps the descriptor set bound).
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;     // depth of this plane
    float unit;      // the splat's fixed-point unit (light_splat_main.glsl, sweep_resolve.comp)
    ivec2 origin;    // first pixel (or ray texel) of the dispatch
    ivec2 extent;    // pixels (or ray texels) it covers
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

// The six state outputs of a shader that writes all of them (the backward sweep, the
// floor, the skeleton), and their stores: `SIX_STATE_OUTPUTS;` declares them, and such a
// shader defines STORE_OUTPUTS(at) as STORE_SIX_STATES(at).
#define SIX_STATE_OUTPUTS \
    PLANE_OUTPUT(0, out_light_colour); \
    PLANE_OUTPUT(1, out_light_direction); \
    PLANE_OUTPUT(2, out_view_position); \
    PLANE_OUTPUT(3, out_view_direction); \
    PLANE_OUTPUT(4, out_colour_opacity); \
    PLANE_OUTPUT(5, out_medium)
#define STORE_SIX_STATES(at) \
    imageStore(light_colour, at, out_light_colour); \
    imageStore(light_direction, at, out_light_direction); \
    imageStore(view_position, at, out_view_position); \
    imageStore(view_direction, at, out_view_direction); \
    imageStore(colour_opacity, at, out_colour_opacity); \
    imageStore(medium, at, out_medium);

// The compute entry point: the invocation's pixel, the plane's work, its stores
// (STORE_OUTPUTS, which the including shader defines from its outputs).
#if SWEEP_COMPUTE
#define COMPUTE_ENTRY \
    void main() { \
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

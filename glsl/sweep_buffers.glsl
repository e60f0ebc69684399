// The six state buffers of the plane sweep, each a 2-layer image array sampled through one
// view of both layers; the read layer comes as a push constant. What each holds (the
// backward transport uses five, the forward one's viewing rays four): sweep_plane_io.glsl. Both layers are always
// valid to the validation layer (GENERAL layout), so nothing is rebound between planes.
#ifndef REFRAKT_SWEEP_BUFFERS_GLSL
#define REFRAKT_SWEEP_BUFFERS_GLSL

// SWEEP_COMPUTE 1: the compute sweep (issue 31). The same images are storage images
// there, read with imageLoad at the read layer and written with imageStore at the other
// (every state read is a texel fetch or a bilinear tap computed here, never hardware
// filtering, so both paths read the same values). STATE_IMAGE declares a binding as the
// path needs it.
#ifndef SWEEP_COMPUTE
#define SWEEP_COMPUTE 0
#endif
#if SWEEP_COMPUTE
#define STATE_IMAGE(b, name) layout(set = 0, binding = b, rgba32f) uniform image2DArray name
#else
#define STATE_IMAGE(b, name) layout(set = 0, binding = b) uniform sampler2DArray name
#endif

STATE_IMAGE(4, light_colour);
STATE_IMAGE(5, light_direction);
STATE_IMAGE(6, view_position);
STATE_IMAGE(7, view_direction);
STATE_IMAGE(8, colour_opacity);
STATE_IMAGE(9, medium);

// The `arrays` lever (specialization constant 5): on, a state value of the read layer is
// one fetch at the push-constant layer; off, the way the sweep first read it, a choice
// between a fetch of layer 0 and one of layer 1 (then through a view per layer).
// llvmpipe (Mesa 22.3) runs both sides of that choice even though the layer is uniform:
// every state read cost two fetches, 19-21 % of a plane and 39 % of the floor kernel
// (issue 16). Kept as the reference for `bench variants`.
layout(constant_id = 5) const bool ARRAY_READS = true;

// Bilinear interpolation with full f32 weights. Hardware filtering quantises the weights
// (8 sub-texel bits on lavapipe, 8 on most GPUs): the light moves a small fraction of a
// texel per plane, and that rounding, repeated every plane, shifted a ball lens' focus by
// more than 10 % (measured). Clamp-to-edge addressing.
struct Bilinear {
    ivec2 texel[4];
    float weight[4];
};

Bilinear bilinear_taps(ivec2 size, vec2 uv) {
    vec2 x = uv * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(x));
    vec2 t = x - vec2(i);
    ivec2 hi = size - 1;
    Bilinear b;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        b.texel[k] = clamp(i + o, ivec2(0), hi);
        b.weight[k] = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
    }
    return b;
}

// The backward plane's light reads: light colour and direction of the read layer, texel
// by texel (FETCH_LIGHT, READ_LIGHT_PIXEL) or bilinearly (READ_BUFFER). A shader that
// defines LIGHT_TILE_READS 1 (the compute sweep's backward plane, sweep.comp) may serve
// them from a workgroup tile (the `tile` lever, issue 31: light_tile_texel,
// sweep_plane_io.glsl); every other shader fetches them from the images.
#ifndef LIGHT_TILE_READS
#define LIGHT_TILE_READS 0
#endif
#if LIGHT_TILE_READS
vec4 light_tile_texel(uint which, ivec2 texel, uint layer);   // 0: colour, 1: direction
#define FETCH_LIGHT(name, which, pixel, layer) light_tile_texel((which), (pixel), (layer))
#else
#define FETCH_LIGHT(name, which, pixel, layer) FETCH_LAYER(name, pixel, layer)
#endif
#define READ_LIGHT_PIXEL(name, which, layer, pixel) FETCH_LIGHT(name, which, pixel, layer)

#if SWEEP_COMPUTE
// Storage images cannot be passed to a function of any image (their format is part of
// the type), so each binding the sweep reads bilinearly gets its own function,
// bilinear_<name> (DEFINE_BILINEAR after the binding's declaration), with the same
// arithmetic as bilinear_layer below.
#define STATE_SIZE(tex) imageSize(tex).xy
#define FETCH_LAYER(tex, pixel, layer) imageLoad(tex, ivec3((pixel), (layer)))
#define DEFINE_BILINEAR(name) \
    vec4 bilinear_##name(uint layer, vec2 uv) { \
        Bilinear b = bilinear_taps(STATE_SIZE(name), uv); \
        vec4 sum = vec4(0.0); \
        for (int k = 0; k < 4; ++k) sum += b.weight[k] * FETCH_LAYER(name, b.texel[k], layer); \
        return sum; \
    }
#define READ_BUFFER(name, layer, uv) bilinear_##name((layer), (uv))
// The light's two images through FETCH_LIGHT (the same taps, weights and order).
#define DEFINE_LIGHT_BILINEAR(name, which) \
    vec4 bilinear_##name(uint layer, vec2 uv) { \
        Bilinear b = bilinear_taps(STATE_SIZE(name), uv); \
        vec4 sum = vec4(0.0); \
        for (int k = 0; k < 4; ++k) \
            sum += b.weight[k] * FETCH_LIGHT(name, which, b.texel[k], layer); \
        return sum; \
    }
DEFINE_LIGHT_BILINEAR(light_colour, 0u)
DEFINE_LIGHT_BILINEAR(light_direction, 1u)
#else
#define STATE_SIZE(tex) textureSize(tex, 0).xy
#define DEFINE_BILINEAR(name)

vec4 bilinear_layer(sampler2DArray tex, uint layer, vec2 uv) {
    Bilinear b = bilinear_taps(textureSize(tex, 0).xy, uv);
    vec4 sum = vec4(0.0);
    for (int k = 0; k < 4; ++k) sum += b.weight[k] * texelFetch(tex, ivec3(b.texel[k], layer), 0);
    return sum;
}

// Fetch texel `pixel` of layer `layer` of `tex` as the `arrays` lever says.
#define FETCH_LAYER(tex, pixel, layer) \
    (ARRAY_READS ? texelFetch(tex, ivec3((pixel), (layer)), 0) \
                 : (layer) == 0u ? texelFetch(tex, ivec3((pixel), 0), 0) \
                                 : texelFetch(tex, ivec3((pixel), 1), 0))

// A state value at an arbitrary position (bilinear) of the read layer.
#define READ_BUFFER(name, layer, uv) \
    (ARRAY_READS ? bilinear_layer(name, (layer), (uv)) \
                 : (layer) == 0u ? bilinear_layer(name, 0u, (uv)) : bilinear_layer(name, 1u, (uv)))
#endif

// A state value of this pixel of the read layer (exact, one fetch).
#define READ_PIXEL(name, layer, pixel) FETCH_LAYER(name, pixel, layer)

#endif

// The grouped point sprites (the `splat=groups` lever, fragment path): the light rays'
// deposits splatted with one point per 2 x 2 rays instead of one per ray, the deposits
// computed by a compute pass: lavapipe runs the vertex stage on one thread, so the
// deposits are computed on all cores and the points are fewer (docs/NOTES.md, "Grouped
// sprites", has the figures). GPUs take the compute sweep; there this lever is untimed.
//
// Per plane: light_splat_groups.comp computes every ray's deposit into `deposits`
// (light_gather.glsl, the compute sweep's layout), and for each group g of rays (2 gi +
// {0, 1}, 2 gj + {0, 1}) the union of their footprints in sprite_groups[g] when it fits
// within SPLAT_GROUP_SPAN pixels a side (else zero: a group whose rays land apart, at a
// silhouette or a fold, would need a point wider than a device may draw). Each of its
// workgroups lists, in order, its groups that fit one sprite and its other groups, leaving
// out those whose deposits miss the image, and writes an indirect draw for each list. The
// splat's render pass then draws the sprites (pc.pad = 0), a point per listed group, and
// the rays (pc.pad = 1), a point per ray of a group in the second list. Every pixel
// receives the same deposits as with a sprite per ray; only the order of the float sums
// differs (a group's four are added before the blend).
#ifndef REFRAKT_LIGHT_SPLAT_GROUPS_GLSL
#define REFRAKT_LIGHT_SPLAT_GROUPS_GLSL

#ifndef SPLAT_GROUP_SPAN
#error "SPLAT_GROUP_SPAN comes from build.rs (src/render/limits.rs)"
#endif

#if DEPOSITS_READONLY
#define GROUP_BUFFER readonly buffer
#else
#define GROUP_BUFFER buffer
#endif

// Per group: the union of its rays' footprints (lo.xy, hi.xy, pixels), or zero.
layout(std430, set = 0, binding = 23) GROUP_BUFFER SpriteGroups {
    vec4 sprite_groups[];
};
// Per workgroup w of light_splat_groups.comp, from slot SPLAT_GROUP_WORKGROUP * w on: its
// groups drawn as one sprite each, then its groups drawn as their rays, each list in the
// groups' order (a group whose deposits miss the image is in neither).
layout(std430, set = 0, binding = 24) GROUP_BUFFER SpriteFallback {
    uint sprite_fallback[];
};
// VkDrawIndirectCommand per workgroup w of W: [w] its groups' rays (vertexCount = 4 * the
// groups, firstVertex = 4 * their first slot), [W + w] its sprites (vertexCount = the
// groups, firstVertex = their first slot); instanceCount = 1, firstInstance = 0.
layout(std430, set = 0, binding = 25) GROUP_BUFFER SpriteDraws {
    uvec4 sprite_draws[];
};

int group_columns() { return (int(P.light_rays.x) + 1) / 2; }
int group_count() { return group_columns() * ((int(P.light_rays.y) + 1) / 2); }
// Ray k (0-3) of group g: (2 gi + (k & 1), 2 gj + (k >> 1)); it may lie past the grid.
ivec2 group_ray(int g, int k) {
    ivec2 gij = ivec2(g % group_columns(), g / group_columns());
    return 2 * gij + ivec2(k & 1, k >> 1);
}

// Whether a stored footprint holds a deposit (an empty one has zero width).
bool deposits_anything(vec4 footprint) { return footprint.z > footprint.x; }

#endif

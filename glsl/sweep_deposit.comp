#version 460
// The compute sweep's splat, first half (light_gather.glsl): each light ray's deposit on
// this plane, and the bounding box of each block of 8 x 8 rays. One workgroup per block.
#extension GL_GOOGLE_include_directive : require
#define SWEEP_COMPUTE 1
#include "sweep_common.glsl"
#include "sweep_buffers.glsl"
#include "sweep_rays.glsl"
#include "light_splat_ray.glsl"
#include "light_gather.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;   // the layer the rays were just written to
    float depth;       // this plane's depth
    float unit;
} pc;

shared vec4 box[64];

void main() {
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy);
    uint t = gl_LocalInvocationIndex;
    vec4 mine = vec4(1e30, 1e30, -1e30, -1e30);
    if (ray_exists(ij)) {
        int r = ray_index(ij);
        RayDeposit d;
        if (ray_deposit(r, pc.read_layer, pc.depth, d)) {
            mine = d.footprint;
        } else {
            clear_deposit(d);   // no deposit: an empty footprint
        }
        store_deposit(r, d);
    }
    // The block's box: a tree reduction over the workgroup.
    box[t] = mine;
    barrier();
    for (uint s = 32u; s > 0u; s >>= 1) {
        if (t < s) {
            vec4 o = box[t + s];
            box[t] = vec4(min(box[t].xy, o.xy), max(box[t].zw, o.zw));
        }
        barrier();
    }
    if (t == 0u) {
        ivec2 b = ivec2(gl_WorkGroupID.xy);
        blocks[b.y * gather_blocks().x + b.x] = box[0];
    }
}

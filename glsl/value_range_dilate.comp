#version 460
// The range over each brick's 3 x 3 x 3 neighbourhood (render::value_ranges): a segment
// that starts in a brick and moves at most one brick along each axis stays inside it, so
// one fetch at its start bounds every value it can meet inside the box (the sweep adds
// the outside's 0 where a step leaves the box).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, rgba32f) uniform readonly image3D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image3D dst;

void main() {
    ivec3 brick = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(src);
    if (any(greaterThanEqual(brick, size))) return;
    vec2 r = vec2(1e30, -1e30);
    for (int k = 0; k < 27; ++k) {
        ivec3 o = ivec3(k % 3, (k / 3) % 3, k / 9) - 1;
        ivec3 c = clamp(brick + o, ivec3(0), size - 1);
        vec2 s = imageLoad(src, c).xy;
        r = vec2(min(r.x, s.x), max(r.y, s.y));
    }
    imageStore(dst, brick, vec4(r, 0.0, 0.0));
}

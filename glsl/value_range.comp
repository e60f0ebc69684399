#version 460
// The range of values around each brick of the volume (render::value_ranges): the
// smallest and largest voxel value over the brick's VALUE_BRICK^3 voxels and a one-voxel
// apron, which is what a trilinear fetch or the 8-corner gradient (value_gradient) at any
// point inside the brick can read, clamped to the volume as those fetches are. The value
// 0 of the outside (value_at_tex) is not included: the sweep adds it where a step leaves
// the box (a slab of matter at the box's side is homogeneous up to the face).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image3D ranges;

void main() {
    ivec3 brick = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(brick, imageSize(ranges)))) return;
    ivec3 dims = textureSize(volume, 0);
    ivec3 lo = brick * VALUE_BRICK - 1;
    ivec3 hi = lo + (VALUE_BRICK + 1);
    float vmin = 1e30, vmax = -1e30;
    ivec3 a = max(lo, ivec3(0)), b = min(hi, dims - 1);
    for (int z = a.z; z <= b.z; ++z) {
        for (int y = a.y; y <= b.y; ++y) {
            for (int x = a.x; x <= b.x; ++x) {
                float v = texelFetch(volume, ivec3(x, y, z), 0).r;
                vmin = min(vmin, v);
                vmax = max(vmax, v);
            }
        }
    }
    imageStore(ranges, brick, vec4(vmin, vmax, 0.0, 0.0));
}

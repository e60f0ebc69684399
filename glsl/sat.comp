#version 460
// Summed-area table of an environment map (thesis sect. 4.4, 5.3), two passes: pass 0
// scans every row (one invocation per row), pass 1 every column (one per column), in place.
// Precision: the map's mean is subtracted first, so the running sums stay near zero instead
// of growing to (pixels x mean), and each scan uses Kahan compensated summation; a plain
// f32 prefix sum over a 2048 x 1024 map loses the 1e-3 relative accuracy box averages need.
// The table stores S(x, y) = sum over [0, x] x [0, y] of (map - mean).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D map;
layout(set = 0, binding = 1, rgba32f) uniform image2D table;
layout(push_constant) uniform Push {
    vec4 mean;
    uint pass_index;
} pc;

void main() {
    ivec2 size = imageSize(table);
    int line = int(gl_GlobalInvocationID.x);
    // `precise`: a driver must not reassociate the Kahan terms away.
    precise vec4 sum = vec4(0.0);
    precise vec4 carry = vec4(0.0);
    if (pc.pass_index == 0u) {
        if (line >= size.y) return;
        for (int x = 0; x < size.x; ++x) {
            precise vec4 v = imageLoad(map, ivec2(x, line)) - pc.mean;
            precise vec4 y = v - carry;
            precise vec4 t = sum + y;
            carry = (t - sum) - y;
            sum = t;
            imageStore(table, ivec2(x, line), sum);
        }
    } else {
        if (line >= size.x) return;
        for (int y = 0; y < size.y; ++y) {
            precise vec4 v = imageLoad(table, ivec2(line, y));
            precise vec4 k = v - carry;
            precise vec4 t = sum + k;
            carry = (t - sum) - k;
            sum = t;
            imageStore(table, ivec2(line, y), sum);
        }
    }
}

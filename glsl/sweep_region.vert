#version 460
// The pixels a plane of the sweep shades on the fragment path (the `region` lever,
// render/refract/region.rs): a convex polygon of at most eight vertices in pixels, pushed
// per plane in normalised device coordinates (the viewport is the whole screen), drawn
// as a fan of six triangles (18 vertices; a polygon of fewer vertices
// repeats its last, and the extra triangles have no area). The render pass's area and
// scissor are the polygon's bounding rectangle. The fragment shaders read the pixel from
// gl_FragCoord, not from a varying.
layout(push_constant) uniform Push {
    uint plane;
    uint read_layer;
    float depth;
    uint pad;
    vec2 region[8];
} pc;

void main() {
    int triangle = gl_VertexIndex / 3;
    int corner = gl_VertexIndex % 3;
    int k = corner == 0 ? 0 : triangle + corner;
    gl_Position = vec4(pc.region[k], 0.0, 1.0);
}

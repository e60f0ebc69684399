#version 460
// Setup pass (thesis ch. 5, Fig. 5.1): initialises both layers of the state images (the
// backward transport's five and the forward one's view_position: sweep_plane_io.glsl).
// Light: uniform colour and direction on "plane -1". Viewing rays: start on plane 0
// along each pixel's camera ray, carrying the scalar value one plane earlier (plane -1)
// so the first segment is integrated like every other. Colour/opacity 0, medium white.
#extension GL_GOOGLE_include_directive : require
#include "sweep_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 4, rgba32f) uniform writeonly image2DArray light_colour;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2DArray light_direction;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2DArray view_position;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2DArray view_direction;
layout(set = 0, binding = 8, rgba32f) uniform writeonly image2DArray colour_opacity;
layout(set = 0, binding = 9, rgba32f) uniform writeonly image2DArray medium;
layout(set = 0, binding = 10, rgba32f) uniform writeonly image2DArray irradiance;
layout(set = 0, binding = 11, rgba32f) uniform writeonly image2DArray irradiance_direction;
layout(set = 0, binding = 12, rgba32f) uniform writeonly image2DArray rays_flux;
layout(set = 0, binding = 13, rgba32f) uniform writeonly image2DArray rays_direction;

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    float d0 = P.planes.x;
    float ds = P.planes.y;
    // Forward transport: ray r = texel (r % image width, r / image width) of the ray
    // images, one ray per cell of a regular grid over the launch plane (plane -1), carrying
    // the flux of its cell (irradiance x cell area, so that the splat of unobstructed rays
    // reads the light colour), its position in .w. Texels past the grid hold no light.
    // The grid's size changes with the camera, so it chooses values here, never a branch:
    // lavapipe (Mesa 22.3) inlines uniforms that decide a branch into the shader and
    // compiles a variant per value, 0.36 s per frame while the camera moves (measured in
    // the viewer with an empty Mesa shader cache); the ray images' size is the image's.
    ivec2 ray_image = imageSize(rays_flux).xy;
    if (P.transport.x > 0.5 && all(lessThan(id, ray_image))) {
        int r = id.y * ray_image.x + id.x;
        ivec2 grid = ivec2(P.light_rays.xy);
        ivec2 ij = ivec2(r % grid.x, r / grid.x);
        bool in_grid = r < grid.x * grid.y;
        vec2 pos = P.light_grid.xy + (vec2(ij) + 0.5) * P.light_grid.zw;
        float eta_l = eta_of(value_at_tex(to_tex(vec3(pos, d0 - ds))));
        vec4 lc = mix(vec4(0.0),
                      vec4(P.light_colour.rgb * (P.light_grid.z * P.light_grid.w), pos.x),
                      bvec4(in_grid));
        vec4 ld = mix(vec4(0.0, 0.0, 1.0, 0.0), vec4(P.light_dir.xyz * eta_l, pos.y),
                      bvec4(in_grid));
        for (int layer = 0; layer < 2; ++layer) {
            imageStore(rays_flux, ivec3(id, layer), lc);
            imageStore(rays_direction, ivec3(id, layer), ld);
        }
    }
    if (any(greaterThanEqual(id, ivec2(P.camera.zw)))) return;
    vec2 uv = (vec2(id) + 0.5) / P.camera.zw;
    vec3 ray = plane_point(uv, 1.0);            // z = 1
    vec3 vp = ray * d0;                          // on plane 0
    float s_prev = value_at_tex(to_tex(ray * (d0 - ds)));
    vec3 vd = normalize(ray) * eta_of(s_prev);   // v = eta dx/ds (eq. 4.2)
    // Backward transport: the light colour and direction on "plane -1" per pixel, with
    // the viewing ray's x and y in w (the compact state: sweep_plane_io.glsl).
    vec4 lc = vec4(P.light_colour.rgb, vp.x);
    vec4 ld = vec4(P.light_dir.xyz, vp.y);
    for (int layer = 0; layer < 2; ++layer) {
        ivec3 at = ivec3(id, layer);
        // The forward transport's irradiance of plane -1 (and a defined other layer).
        imageStore(irradiance, at, vec4(P.light_colour.rgb, 0.0));
        imageStore(irradiance_direction, at, vec4(P.light_dir.xyz, 1.0));
        imageStore(light_colour, at, lc);
        imageStore(light_direction, at, ld);
        imageStore(view_position, at, vec4(vp.xy, 0.0, 0.0));   // forward: x, y
        imageStore(view_direction, at, vec4(vd, s_prev));
        imageStore(colour_opacity, at, vec4(0.0));
        imageStore(medium, at, vec4(1.0, 1.0, 1.0, VIEW_RAY_AT_SETUP));
    }
}

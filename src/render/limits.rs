// The one definition of the limits the shaders share with the host. build.rs includes
// this file and passes each constant to every shader as a preprocessor macro of the same
// name, so Rust and GLSL cannot disagree (plain `//` comments: the file is `include!`d
// into build.rs, where inner doc comments are not allowed).

/// Light and viewing rays may deviate from the sweep direction by at most this much
/// (the cosine: ~84.3°): they must reach the next plane (thesis ch. 7). Directions are
/// bent no further, and the light may not be set further from the view.
pub const MIN_FORWARD: f32 = 0.1;

// The compute sweep's gather splat (glsl/light_gather.glsl): rays are binned by the screen
// tiles of GATHER_TILE pixels (the gather's workgroup side) their deposits overlap, or,
// when a deposit spans more than 2 x 2 of those, by coarse tiles of GATHER_COARSE_TILE
// pixels (a multiple of GATHER_TILE), or else into one bin every tile reads.
pub const GATHER_TILE: u32 = 8;
pub const GATHER_COARSE_TILE: u32 = 64;

// The light rays' empty-space test (render::value_ranges, glsl/value_range*.comp): the
// volume in bricks of VALUE_BRICK^3 voxels, each with the range of values around it.
pub const VALUE_BRICK: u32 = 4;

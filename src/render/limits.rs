// The one definition of the limits the shaders share with the host. build.rs includes
// this file and passes each constant to every shader as a preprocessor macro of the same
// name, so Rust and GLSL cannot disagree (plain `//` comments: the file is `include!`d
// into build.rs, where inner doc comments are not allowed).

/// Light and viewing rays may deviate from the sweep direction by at most this much
/// (the cosine: ~84.3°): they must reach the next plane (thesis ch. 7). Directions are
/// bent no further, and the light may not be set further from the view.
pub const MIN_FORWARD: f32 = 0.1;

// The compute sweep's gather splat (glsl/sweep_gather.comp): a tile's list of blocks of
// 8 x 8 light rays in shared memory, filled in buckets of at most that many blocks, so
// at most GATHER_LIST * GATHER_BUCKETS blocks (16.7 M rays) per frame.
pub const GATHER_LIST: u32 = 2048;
pub const GATHER_BUCKETS: u32 = 128;

// The light rays' empty-space test (render::value_ranges, glsl/value_range*.comp): the
// volume in bricks of VALUE_BRICK^3 voxels, each with the range of values around it.
pub const VALUE_BRICK: u32 = 4;

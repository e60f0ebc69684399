// The one definition of the limits the shaders share with the host. build.rs includes
// this file and passes each constant to every shader as a preprocessor macro of the same
// name, so Rust and GLSL cannot disagree (plain `//` comments: the file is `include!`d
// into build.rs, where inner doc comments are not allowed).

/// Light and viewing rays may deviate from the sweep direction by at most this much
/// (the cosine: ~84.3°): they must reach the next plane (thesis ch. 7). Directions are
/// bent no further, and the light may not be set further from the view.
pub const MIN_FORWARD: f32 = 0.1;

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
// when a deposit spans more than GATHER_FINE_SPAN of those a side, by coarse tiles of
// GATHER_COARSE_TILE pixels (a multiple of GATHER_TILE), or else into one bin every tile
// reads. Every fine tile reads its coarse tile's whole bin: coarse tiles of 32 pixels (a
// deposit of up to 2 * MAX_SPLAT_HALF_WIDTH = 32 pixels spans at most two a side) are
// read by 16 fine tiles, not 64 (H100, supernova row: 621 ms a frame against 677 with
// 64-pixel ones). A fine span of 3 (a ray listed up to 9 times) was no faster (628 ms).
pub const GATHER_TILE: u32 = 8;
pub const GATHER_COARSE_TILE: u32 = 32;
pub const GATHER_FINE_SPAN: u32 = 2;
// The pair gather (glsl/sweep_gather.comp) sums a tile's candidate rays in chunks of this
// many, one workgroup per chunk.
pub const GATHER_CHUNK: u32 = 256;

// The compute sweep's scatter of ray blocks (`gather=blocks`, glsl/sweep_scatter.glsl):
// each workgroup of 8 x 8 light rays sums its deposits into a tile of SCATTER_TILE x
// SCATTER_TILE pixels in shared memory (seven 64-bit sums a pixel: 7.9 KiB at 12, beside
// the half block's deposits within the 16 KiB every device gives a workgroup), then adds
// the tile into the plane's sums. At 2 rays a pixel a block of smooth wavefront covers
// about 8 x 5 pixels plus its boxes' overhang, so the tile holds it spread by half again.
pub const SCATTER_TILE: u32 = 12;

// The grouped point sprites (the `splat=groups` lever, glsl/light_splat_groups.glsl): one
// sprite per 2 x 2 light rays whose deposits fit within SPLAT_GROUP_SPAN pixels a side
// (its point then at most SPLAT_GROUP_SPAN + 1 wide, below the 64 every device draws);
// the rays of any other group get a sprite each. SPLAT_GROUP_WORKGROUP groups per
// workgroup of the pass that sorts them, each writing one indirect draw of its others.
pub const SPLAT_GROUP_SPAN: u32 = 4;
pub const SPLAT_GROUP_WORKGROUP: u32 = 64;

// The light rays' empty-space test (render::value_ranges, glsl/value_range*.comp): the
// volume in bricks of VALUE_BRICK^3 voxels, each with the range of values around it.
pub const VALUE_BRICK: u32 = 4;

// Samples per transfer function on the GPU (transfer::TF_SAMPLES): fine enough that linear
// interpolation between samples is within 1e-4 of the piecewise-linear function for
// slopes up to ~100 per unit s away from control points.
pub const TF_SAMPLES: u32 = 4096;

// Entries per axis of the preintegration table (render::preintegration::TABLE_SIZE).
pub const PREINT_SIZE: u32 = 256;

// Most lights the ambient-scattering model takes (the main light and three more): its
// radiance cache holds one light per channel of an RGBA image, so at most 4.
pub const MAX_LIGHTS: usize = 4;
const _: () = assert!(MAX_LIGHTS <= 4);

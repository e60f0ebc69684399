// The eikonal light simulator's shared declarations (issue 35; seed 001, Ihrke et al.,
// sect. 4.2 and 5.2): a wavefront of patches, four corner particles each, advanced by the
// equi-temporal ray equation (eqs. 14-15, ray_equation.glsl), each patch carrying its flux
// (the intensity law, eqs. 16-18: irradiance = flux / area, so the flux of a stream tube
// is constant but for attenuation), tessellated where it grows past a voxel and retired
// where its light is gone or has left the box. One cycle is four dispatches, all with this
// file's bindings and push constants (one descriptor set):
//   light_wavefront_step.comp        advance each patch `substeps` times, depositing its
//                                    light, then classify it: 0 (retire), 1 (keep) or
//                                    ku kv (split into ku x kv);
//   light_wavefront_scan_blocks.comp exclusive prefix sum of the counts per 256 patches;
//   light_wavefront_scan_sums.comp   prefix sum of the blocks' totals (one workgroup), the
//                                    next list's size and its indirect dispatch;
//   light_wavefront_emit.comp        write each patch's 0, 1 or ku kv patches into the other
//                                    half of the list, at its offset;
// and once before the first cycle, light_wavefront_clear.comp (the clear-space cells).
// src/render/light_simulator.rs records them and documents the units.
#ifndef REFRAKT_LIGHT_WAVEFRONT_GLSL
#define REFRAKT_LIGHT_WAVEFRONT_GLSL
#extension GL_GOOGLE_include_directive : require

// Patches per workgroup in every kernel (the scans' block size).
#define WAVEFRONT_GROUP 256

layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1) uniform sampler1DArray tf;

// A patch: corners 0, 1, 2, 3 counter-clockwise seen along the light (at launch), as
// parameters (0, 0), (1, 0), (1, 1), (0, 1) of the bilinear patch. Corner k: position x[k]
// (world) and v[k] = eta dx/ds (|v| = eta). The spare w components:
//   x[0].w  the patch's share of the launched flux, unattenuated (voxel-flux units), so
//           the transmittance of channel c is flux[c] / (share * colour[c]);
//   x[1].w  its tessellation level (0 at launch; a split adds 1);
//   x[2].w  the sign of its oriented area (+1 at launch; it turns at each focus crossed);
//   x[3].w  its children for the emit, ku + 8 kv along its two parameters (0: retired);
//   v[0].w  foci crossed;
//   v[1].w  the receivers it has reached, a bit mask (light_wavefront_step.comp);
//   v[2].w  its launched patch's share (x[0].w at launch).
// flux: rgb, in units of the light's irradiance times a reference step squared (a patch
// one reference step on a side, square to the light, unattenuated, carries `colour`).
struct Patch {
    vec4 x[4];
    vec4 v[4];
    vec4 flux;
};

// The list: two halves of `capacity` patches, each a buffer of its own (so each may take
// the device's whole storage-buffer range); a cycle reads and updates this cycle's half
// (`patches`, binding 2) and writes the next list into the other (`patches_next`, binding
// 12): the host binds them the other way round on odd cycles.
layout(std430, set = 0, binding = 2) buffer Patches {
    Patch patches[];
};
layout(std430, set = 0, binding = 12) buffer PatchesNext {
    Patch patches_next[];
};

// Each patch's count of patches in the next list (step), turned into its offset within
// its block (scan_blocks).
layout(std430, set = 0, binding = 3) buffer Counts {
    uint counts[];
};

// Per block of WAVEFRONT_GROUP patches: its total, then its offset (scan_sums).
layout(std430, set = 0, binding = 4) buffer BlockSums {
    uint block_sums[];
};

// Words of the control buffer (src/render/light_simulator.rs reads the same offsets).
#define CTRL_DISPATCH 0u        // [2] x 4 words: indirect dispatch (x, 1, 1, unused) per half
#define CTRL_COUNT 8u           // [2]: patches in each half
#define CTRL_NEEDED 10u         // the largest next list the capacity could not hold
#define CTRL_WORST_SPAN 11u     // float bits: the longest edge of a kept patch (voxels)
#define CTRL_UNSPLIT 12u        // patches longer than a voxel kept whole at the level limit
#define CTRL_FOCI 13u           // foci crossed (patch orientation turned), all cycles
#define CTRL_COARSE 14u         // receiver deposits too wide for the exact coverage
#define CTRL_PEAK 15u           // the largest list
// 32.32 fixed-point sums (two words each, light_splat_fixed.glsl), rgb, voxel-flux units:
#define CTRL_ABSORBED 16u       // retired below the energy threshold
#define CTRL_LEFT 22u           // retired leaving the box
#define CTRL_AT_FOCI 28u        // carried through a focus (kept) or discarded there
#define CTRL_DROPPED 34u        // lost to the capacity (not written)
#define CTRL_TORN 40u           // retired torn (longer than tear_span)
#define CTRL_DILUTED 46u        // retired split below min_dilution of its launched flux
#define CTRL_PATCH_CYCLES 52u   // patch-cycles advanced, all cycles (scan_sums adds)
#define CTRL_STRAIGHT 53u       // of them, in clear space (straight lines)
#define CTRL_WORDS 54u
layout(std430, set = 0, binding = 5) buffer Control {
    uint control[];
};

// Receivers: planes the light's flux is counted on where it crosses them (forward, along
// the plane's normal), per pixel, three 32.32 channels, receiver by receiver, each
// channel-major. Geometry in `receivers`: per receiver four vec4: origin (pixel (0, 0)'s
// corner; w: width), u (one pixel along x; w: height), v (one pixel along y; w: its first
// sum: three times the pixels of the receivers before it), n (unit normal; w: n . x on
// the plane).
layout(std430, set = 0, binding = 6) buffer ReceiverSums {
    uint receiver_sums[];
};
layout(std430, set = 0, binding = 7) readonly buffer Receivers {
    vec4 receivers[];
};

// The field texture (glsl/field.comp): value and grad eta_tf per voxel, filtered: the
// corners' eta and grad eta (ray_equation.glsl with RAY_FIELD).
layout(set = 0, binding = 9) uniform sampler3D field;
// Whether the corners read eta and grad eta from it (RayGradient::FieldTexture) or
// difference the trilinear field as the photon tracer does (RayGradient::Differences).
layout(constant_id = 0) const bool WAVEFRONT_FIELD = false;

// The fluence volume: per voxel six 32.32 channels, the light crossing it per unit volume
// (rgb: sum of flux x path length / voxel volume, in the light's irradiance units) and the
// luminance-weighted direction (xyz), channel-major as the splat's sums.
layout(std430, set = 0, binding = 8) buffer FluenceSums {
    uint fluence_sums[];
};

// Clear space, the fast path of light_wavefront_step.comp (straight_cycle): per cell of
// the trilinear field (cell c: voxels c to c + 1 along each axis, clamped), eta where one
// eta holds throughout the cells within CLEAR_REACH of it, 0 where it may vary. Built
// once per simulation by light_wavefront_clear.comp into `clear_cells` (the cells' own
// eta, then dilated along x, y and z in turn through `clear_scratch`); the step reads
// `clear_cells`. Corners whose whole cycle stays where eta is one move in straight lines.
layout(set = 0, binding = 10, r32f) uniform image3D clear_cells;
layout(set = 0, binding = 11, r32f) uniform image3D clear_scratch;
// Whether corners take the fast path (WavefrontSettings::clear_space).
layout(constant_id = 1) const bool WAVEFRONT_CLEAR = true;
// Whether the step deposits into the fluence volume (WavefrontSettings::fluence): a
// specialization constant, not a push constant, because llvmpipe runs both sides of a
// branch even where its condition is uniform (the deposits' atomics, masked off, cost as
// much as when they add).
layout(constant_id = 3) const bool WAVEFRONT_FLUENCE = false;
// Whether the corners take eta from the cubic B-spline of the values (RayGradient::Cubic,
// ray_equation.glsl's RAY_CUBIC) instead of the trilinear field.
layout(constant_id = 4) const bool WAVEFRONT_CUBIC = false;
// Cells the dilation reaches along each axis: a corner moving at most 3 voxels per axis
// in a cycle, with the gradient's differences 0.05 voxels either side and the trilinear
// cell around each point, reads cells at most 4 from its start's; the cubic B-spline
// reads one voxel more either side of the cell, so one cell more.
#define CLEAR_REACH (WAVEFRONT_CUBIC ? 5 : 4)

layout(push_constant) uniform Push {
    vec4 half_extent;  // xyz: the box's half extent; w: the reference step (world)
    vec4 dims;         // xyz: voxels per axis; w: the eta scale k
    vec4 colour;       // rgb: the light's colour; w: the energy threshold (transmittance)
    float dt;          // optical path per substep (world)
    uint substeps;     // substeps per cycle
    uint capacity;     // patches per half of the list
    uint parity;       // the half this cycle reads
    uint receiver_count;
    uint max_level;    // tessellation levels at most
    uint discard_at_foci;  // 1: retire a patch that crossed a focus (the paper); 0: keep
    float tear_span;   // a patch longer than this (reference steps) is torn: retired
    float min_dilution;  // a patch below this part of its launched share retires
} pc;

#define RAY_VOLUME volume
#define RAY_TF tf
#define RAY_HALF pc.half_extent.xyz
#define RAY_DIMS pc.dims.xyz
#define RAY_REF_STEP pc.half_extent.w
#define RAY_ETA_SCALE pc.dims.w
#define RAY_FIELD field
#define RAY_CUBIC WAVEFRONT_CUBIC
#define RAY_USE_FIELD WAVEFRONT_FIELD
#include "ray_equation.glsl"

#endif

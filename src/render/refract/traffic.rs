//! The bytes model: the state traffic one plane fetches and writes, and the part of it
//! no sweep over the present state can avoid (printed by `render -v`, carried by
//! `bench thesis` rows).

use super::*;

impl SweepPass {
    /// State-buffer traffic of one plane (see [`SweepStats::bytes_per_plane`]): every
    /// texel the plane shaders fetch or write, as glsl/sweep_plane.glsl does per shaded
    /// pixel (and, forward, per light ray), for the frame's features and levers.
    pub fn bytes_per_plane(&self, f: TrafficInputs) -> u64 {
        // A choice between two layers fetches both on llvmpipe (the `arrays` lever off).
        let fetch = if f.features.arrays { 1 } else { 2 };
        let pixel = 1;
        let bilinear = 4;
        // Highlights read the light at the face (two bilinear reads), counted for every
        // shaded pixel: an upper bound, what a SIMD driver running the branch fetches.
        let specular = if f.features.specular { 2 * bilinear } else { 0 };
        // The viewing rays: their four buffers, the light and its direction at the
        // segment (bilinear), the highlight's.
        let view_reads = 4 * pixel + 2 * bilinear + specular;
        let texels_per_pixel = if f.forward {
            // Render-pass load and store of the four viewing-ray attachments.
            8 + fetch * view_reads
        } else {
            // Load and store of the five attachments (the compact state,
            // glsl/sweep_plane_io.glsl); the light direction here; per soft-kernel tap
            // the four texels of light colour and of direction. (The viewing ray's four
            // reads: its x in the light colour's texel, its y in the light direction's,
            // already read, and its three images.)
            let taps = if f.features.soft_light { 3 } else { 1 };
            10 + fetch * (pixel + taps * 2 * bilinear + view_reads)
        };
        let mut texels = f.shaded_pixels * texels_per_pixel;
        if f.forward {
            // Per light ray: its two texels and, with softness, four neighbours' flux;
            // load and store of the two ray attachments; the splat reads the ray and its
            // four neighbours' positions (two texels each).
            let ray_reads = 2 + if f.soft { 4 } else { 0 } + 2 + 4 * 2;
            texels += f.light_rays * (4 + fetch * ray_reads);
            if f.compute_splat {
                // The resolve, over the viewport: the sums' 14 words read and zeroed
                // (7 texels' worth) and two texels written. (Neither splat's deposits
                // are counted: how many pixels a ray's box covers is known on the GPU
                // only.)
                texels += f.viewport_pixels * 9;
            }
        }
        texels * STATE_BYTES_PER_PIXEL
    }

    /// The compulsory part of a plane's state traffic (see
    /// [`SweepStats::compulsory_bytes_per_plane`]): each state texel the plane needs, read
    /// once and written once, in the state's present layout (RGBA32F texels). Backward:
    /// the five images of the compact state per shaded pixel (160 B; Algorithm 1's 19
    /// scalars and the skin chain fill them). Forward: the four viewing-ray images and
    /// the irradiance's two per shaded pixel (read), the irradiance written over the
    /// viewport by the splat, and each light ray's two texels.
    pub fn compulsory_bytes_per_plane(&self, f: TrafficInputs) -> u64 {
        let texels = if f.forward {
            f.shaded_pixels * (4 * 2 + 2) + f.viewport_pixels * 2 + f.light_rays * 2 * 2
        } else {
            f.shaded_pixels * StateBuffer::BACKWARD.len() as u64 * 2
        };
        texels * STATE_BYTES_PER_PIXEL
    }
}

/// What [`SweepPass::bytes_per_plane`] counts for.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TrafficInputs {
    pub(crate) features: Features,
    pub(crate) forward: bool,
    pub(crate) soft: bool,
    /// Mean pixels a plane shades.
    pub(crate) shaded_pixels: u64,
    /// Light rays a plane advances (forward): the grid's, or with `rays=needed` the mean
    /// number in the rows the planes move.
    pub(crate) light_rays: u64,
    /// The `splat=compute` lever (forward), and the viewport its resolve covers.
    pub(crate) compute_splat: bool,
    pub(crate) viewport_pixels: u64,
}

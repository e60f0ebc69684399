//! The pixels each plane shades (the `region` lever, issue 16 item 1).
//!
//! Plane i shades the bounding rectangle of the screen projection of the volume box cut to
//! the depths from plane −1 (where the viewing rays' first segment starts) to a little
//! beyond plane i + 1 (the pass moves its rays on to plane i + 1 and probes the value
//! [`REACH_STEPS`] reference steps around them), widened by [`MARGIN_PX`] and that reach. The rectangles only grow from plane to plane, so a pixel is
//! either shaded on every plane from its first on, or has never been shaded: then its
//! camera ray has not met the box yet (the rectangle bounds every box point's projection
//! up to that depth), and its state is still the setup's — a straight camera ray and the
//! light as it arrives from outside the volume. Both are exact there:
//! - the viewing ray moved straight through empty space; the plane shader steps it up to
//!   this plane on its first shaded plane, plane by plane with the sweep's own arithmetic
//!   (glsl/sweep_plane.glsl), so the images equal the full-screen sweep's (measured: bit
//!   for bit, tests/levers.rs);
//! - light read outside the region by a shaded pixel (the backward step's source point,
//!   its soft kernel, a highlight's offset) is light at a point outside the box, before it
//!   enters it: the box is convex and light travels forward, so light that left the box
//!   cannot come back into it, and light that has not entered yet is the unattenuated
//!   light of the setup.
//!
//! Pixels beside the box on the light's far side (in the box's shadow, outside the volume)
//! keep the unattenuated light instead of the shadow; nothing samples them except the soft
//! kernel's outer taps near the box's edge (the bound in tests/levers.rs covers it).
//!
//! What the region saves: the fraction of the viewport outside each plane's rectangle,
//! which the thesis' full-screen quad shades for nothing (63–71 % of the fragments on the
//! thesis scenes; issue 16).

use glam::{Mat4, Vec3};

use super::Planes;
use crate::vk::Area;

/// Pixels added around each rectangle: the bilinear reads of the state straddle one
/// pixel, the composite's environment footprint reads the next one.
pub(crate) const MARGIN_PX: f32 = 2.0;

/// Reference steps beyond the box that a plane's pass still reads it: the face probes
/// (2.5 steps beside a step's centre, and 1.5 further) and a voxel of central
/// differences, rounded up.
pub(crate) const REACH_STEPS: f32 = 5.0;

/// One rectangle per plane (monotonically growing), and the mean fraction of the viewport
/// they cover. `view_to_tex` maps view space to the box's texture coordinates [0, 1]³;
/// `tan_half` and `aspect` are the camera's (glsl/sweep_common.glsl `plane_point`).
pub(crate) fn plane_regions(
    view_to_tex: Mat4,
    planes: &Planes,
    ref_step: f32,
    tan_half: f32,
    aspect: f32,
    size: [u32; 2],
) -> (Vec<Area>, f64) {
    let box_edges = BoxEdges::new(view_to_tex);
    let [w, h] = [size[0] as f32, size[1] as f32];
    let to_pixel = |p: Vec3| {
        let x = (p.x / (p.z * tan_half * aspect) * 0.5 + 0.5) * w;
        let y = (-p.y / (p.z * tan_half) * 0.5 + 0.5) * h;
        (x, y)
    };
    let z_lo = planes.first_depth - planes.spacing - 1e-3 * planes.spacing;
    // How far beside the box a plane's pass reads it (glsl/sweep_plane.glsl: the face
    // probes 2.5 reference steps plus 1.5 further out); projected at the nearest depth
    // (where a world length covers the most pixels) for the lateral margin.
    let reach = REACH_STEPS * ref_step;
    let margin = MARGIN_PX + reach * h / (2.0 * z_lo.max(1e-6) * tan_half);
    let full = Area::full(size[0], size[1]);
    let mut grown: Option<(f32, f32, f32, f32)> = None;
    let mut out = Vec::with_capacity(planes.count as usize);
    let mut covered = 0.0f64;
    for i in 0..planes.count {
        // Widened by a little so a face of the box lying on a plane (a face-on view: the
        // first plane is the box's nearest depth) counts, whatever the rounding.
        // Plane i's pass also moves its viewing rays on to plane i + 1 and probes the
        // value up to REACH beyond (the face test), and reads central differences a voxel
        // around its points: the box counts that far ahead.
        let eps = 1e-3 * planes.spacing;
        let z_hi = planes.depth(i) + planes.spacing + reach + eps;
        let points = box_edges.slab_points(z_lo, z_hi);
        for p in points.into_iter().filter(|p| p.z > 0.0) {
            let (x, y) = to_pixel(p);
            grown = Some(match grown {
                None => (x, y, x, y),
                Some((x0, y0, x1, y1)) => (x0.min(x), y0.min(y), x1.max(x), y1.max(y)),
            });
        }
        let area = match grown {
            // Nothing of the box yet: one pixel keeps the render pass valid (a pixel
            // shaded early and skipped later stays exact: see the module docs).
            None => Area {
                x: 0,
                y: 0,
                width: 1,
                height: 1,
            },
            Some((x0, y0, x1, y1)) => {
                let x0 = (x0 - margin).floor().clamp(0.0, w - 1.0) as u32;
                let y0 = (y0 - margin).floor().clamp(0.0, h - 1.0) as u32;
                let x1 = (x1 + margin).ceil().clamp(x0 as f32 + 1.0, w) as u32;
                let y1 = (y1 + margin).ceil().clamp(y0 as f32 + 1.0, h) as u32;
                Area {
                    x: x0,
                    y: y0,
                    width: x1 - x0,
                    height: y1 - y0,
                }
            }
        };
        debug_assert!(area.x + area.width <= full.width && area.y + area.height <= full.height);
        covered += area.width as f64 * area.height as f64 / (w as f64 * h as f64);
        out.push(area);
    }
    let mean = if out.is_empty() {
        1.0
    } else {
        covered / out.len() as f64
    };
    (out, mean)
}

/// View space (the camera at the origin looking along +z) to world space, and to the box's
/// texture coordinates [0, 1]³, for a box of half extents `half` centred on the origin.
pub(crate) fn view_matrices(camera: &crate::render::Camera, half: Vec3) -> (Mat4, Mat4) {
    let (eye, forward, right, up) = camera.frame();
    let view_to_world = Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        forward.extend(0.0),
        eye.extend(1.0),
    );
    let to_tex = Mat4::from_translation(Vec3::splat(0.5)) * Mat4::from_scale(0.5 / half);
    (view_to_world, to_tex * view_to_world)
}

/// The volume box in view space: its corners and edges.
pub(crate) struct BoxEdges {
    corners: [Vec3; 8],
    edges: Vec<(Vec3, Vec3)>,
}

impl BoxEdges {
    /// `view_to_tex` maps view space to the box's texture coordinates [0, 1]³.
    pub(crate) fn new(view_to_tex: Mat4) -> Self {
        let tex_to_view = view_to_tex.inverse();
        let corners: [Vec3; 8] = std::array::from_fn(|k| {
            let t = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32);
            tex_to_view.transform_point3(t)
        });
        let edges = (0..8usize)
            .flat_map(|a| {
                [1usize, 2, 4]
                    .into_iter()
                    .filter(move |bit| a & bit == 0)
                    .map(move |bit| (a, a | bit))
            })
            .map(|(a, b)| (corners[a], corners[b]))
            .collect();
        BoxEdges { corners, edges }
    }

    /// The vertices of box ∩ {z_lo ≤ z ≤ z_hi}: the corners inside the slab and the
    /// edges' crossings of its two faces (the box is convex: their bounding rectangle is
    /// the slab's part of the box's).
    pub(crate) fn slab_points(&self, z_lo: f32, z_hi: f32) -> Vec<Vec3> {
        let mut points: Vec<Vec3> = self
            .corners
            .iter()
            .copied()
            .filter(|c| c.z >= z_lo && c.z <= z_hi)
            .collect();
        for &(a, b) in &self.edges {
            for z in [z_lo, z_hi] {
                if (a.z - z) * (b.z - z) < 0.0 {
                    points.push(a + (b - a) * ((z - a.z) / (b.z - a.z)));
                }
            }
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Camera;

    fn regions(camera: &Camera, half: Vec3, spacing: f32, side: u32) -> (Vec<Area>, Planes) {
        let planes = Planes::for_box(camera, half, spacing).unwrap();
        let (_, view_to_tex) = view_matrices(camera, half);
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let (r, _) = plane_regions(view_to_tex, &planes, 0.01, tan_half, 1.0, [side, side]);
        (r, planes)
    }

    /// Every point of the box at or before plane i's depth projects inside plane i's
    /// rectangle (sampled densely, independently of the vertex construction), and the
    /// rectangles only grow.
    #[test]
    fn rectangles_bound_the_box_up_to_each_plane_and_grow() {
        for (az, el) in [(0.0, 0.0), (35.0, 40.0), (-60.0, 4.0), (120.0, -30.0)] {
            let camera = Camera {
                azimuth: az,
                elevation: el,
                distance: 4.0,
                ..Default::default()
            };
            let half = Vec3::new(0.5, 0.3, 0.4);
            let side = 64;
            let (areas, planes) = regions(&camera, half, 0.05, side);
            let (eye, forward, right, up) = camera.frame();
            let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
            let n = 24;
            for i in 0..planes.count as usize {
                let a = areas[i];
                if i > 0 {
                    let b = areas[i - 1];
                    assert!(a.x <= b.x && a.y <= b.y, "plane {i} shrank");
                    assert!(a.x + a.width >= b.x + b.width && a.y + a.height >= b.y + b.height);
                }
                for k in 0..n * n * n {
                    let f = Vec3::new(
                        (k % n) as f32 / (n - 1) as f32,
                        ((k / n) % n) as f32 / (n - 1) as f32,
                        (k / (n * n)) as f32 / (n - 1) as f32,
                    );
                    let world = (f * 2.0 - 1.0) * half;
                    let d = world - eye;
                    let z = d.dot(forward);
                    if z > planes.depth(i as u32) || z < planes.first_depth - planes.spacing {
                        continue;
                    }
                    // Off-screen points are bounded by the screen's edge.
                    let s = side as f32;
                    let x = ((d.dot(right) / (z * tan_half) * 0.5 + 0.5) * s).clamp(0.0, s);
                    let y = ((-d.dot(up) / (z * tan_half) * 0.5 + 0.5) * s).clamp(0.0, s);
                    assert!(
                        x >= a.x as f32 && x <= (a.x + a.width) as f32,
                        "az {az} el {el} plane {i}: x {x} outside {a:?}"
                    );
                    assert!(
                        y >= a.y as f32 && y <= (a.y + a.height) as f32,
                        "az {az} el {el} plane {i}: y {y} outside {a:?}"
                    );
                }
            }
            // The last plane's rectangle is the whole box's, which a box seen from 4
            // away does not fill the screen with.
            let last = areas.last().unwrap();
            assert!((last.width * last.height) < side * side, "{last:?}");
        }
    }
}

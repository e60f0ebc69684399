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
) -> PlaneRegions {
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
    // The bounds of x + y and of x − y over the same points: the octagon's diagonals.
    let mut diagonals: Option<[f32; 4]> = None;
    let mut out = Vec::with_capacity(planes.count as usize);
    let mut polygons = Vec::with_capacity(planes.count as usize);
    let mut covered = 0.0f64;
    let mut covered_polygons = 0.0f64;
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
            let (s, d) = (x + y, x - y);
            diagonals = Some(match diagonals {
                None => [s, s, d, d],
                Some([s0, s1, d0, d1]) => [s0.min(s), s1.max(s), d0.min(d), d1.max(d)],
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
        // The diagonals widened as the rectangle is, by the margin and the pixel a
        // rounding outward adds (a point within that distance of the box's projection in
        // any direction is inside: √2 × it along a diagonal's normal (1, ±1)).
        let polygon = RegionPolygon::new(
            area,
            diagonals.map(|[s0, s1, d0, d1]| {
                let m = (margin + 1.0) * std::f32::consts::SQRT_2;
                [s0 - m, s1 + m, d0 - m, d1 + m]
            }),
        );
        covered += area.width as f64 * area.height as f64 / (w as f64 * h as f64);
        covered_polygons += polygon.area() / (w as f64 * h as f64);
        out.push(area);
        polygons.push(polygon);
    }
    let mean = |sum: f64| {
        if out.is_empty() {
            1.0
        } else {
            sum / out.len() as f64
        }
    };
    PlaneRegions {
        rect_fraction: mean(covered),
        polygon_fraction: mean(covered_polygons),
        rects: out,
        polygons,
    }
}

/// The vertices of a plane's draw over its polygon: a fan of six triangles over the
/// polygon's eight vertices (glsl/sweep_region.vert).
pub(crate) const REGION_VERTICES: u32 = 18;

/// Each plane's rectangle and polygon ([`plane_regions`]), and the mean fraction of the
/// viewport each covers.
pub(crate) struct PlaneRegions {
    pub(crate) rects: Vec<Area>,
    pub(crate) polygons: Vec<RegionPolygon>,
    pub(crate) rect_fraction: f64,
    pub(crate) polygon_fraction: f64,
}

/// The pixels a plane's draw covers on the fragment path (the `region=octagon` lever):
/// its rectangle cut by the bounds of x + y and of x − y (pixel coordinates) of the same
/// box points, widened alike — an octagon at most. The box's part up to a plane projects
/// to a convex polygon of up to ten vertices; seen obliquely, its bounding rectangle's
/// corners are empty and the diagonals cut most of them off. Like the rectangles, these
/// only grow from plane to plane (every bound is over a growing set of points, and the
/// polygon is exactly the rectangle ∩ four half-planes), so a pixel outside one has never
/// been shaded and holds the setup's state. glsl/sweep_region.vert draws it as a fan of
/// six triangles from its vertices (push constants).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RegionPolygon {
    /// In order around the polygon, the last repeated up to eight (the fan's extra
    /// triangles have no area).
    pub(crate) vertices: [[f32; 2]; 8],
    /// The bounds that made it: the rectangle x0, y0, x1, y1 and the diagonals' min and
    /// max of x + y, min and max of x − y.
    rect: [f32; 4],
    diagonals: [f32; 4],
}

impl RegionPolygon {
    /// The rectangle `area` cut by `diagonals` (none: the rectangle itself).
    pub(crate) fn new(area: Area, diagonals: Option<[f32; 4]>) -> Self {
        let [x0, y0] = [area.x as f32, area.y as f32];
        let [x1, y1] = [x0 + area.width as f32, y0 + area.height as f32];
        let mut poly = vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
        let diagonals = diagonals.unwrap_or([f32::MIN, f32::MAX, f32::MIN, f32::MAX]);
        let [s0, s1, d0, d1] = diagonals;
        // Sutherland–Hodgman: keep the side where a·(x, y) ≥ c, for each half-plane. The
        // rectangle's four sides and four cuts: at most eight vertices.
        for (a, c) in [
            ([1.0, 1.0], s0),
            ([-1.0, -1.0], -s1),
            ([1.0, -1.0], d0),
            ([-1.0, 1.0], -d1),
        ] {
            let side = |p: [f32; 2]| a[0] * p[0] + a[1] * p[1] - c;
            let mut next = Vec::with_capacity(poly.len() + 1);
            for k in 0..poly.len() {
                let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
                let (sp, sq) = (side(p), side(q));
                if sp >= 0.0 {
                    next.push(p);
                }
                if (sp >= 0.0) != (sq >= 0.0) {
                    let t = sp / (sp - sq);
                    next.push([p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t]);
                }
            }
            poly = next;
        }
        // Empty where the box's projection is off the screen (the rectangle is clamped to
        // it, and kept a pixel wide for the render pass; its pixels cannot see the box):
        // then the fan has no area and the plane draws nothing, which is exact.
        debug_assert!(poly.len() <= 8, "{poly:?}");
        let last = poly.last().copied().unwrap_or([x0, y0]);
        let vertices = std::array::from_fn(|k| poly.get(k).copied().unwrap_or(last));
        RegionPolygon {
            vertices,
            rect: [x0, y0, x1, y1],
            diagonals,
        }
    }

    /// The vertices in normalised device coordinates of a viewport of `size` pixels (what
    /// glsl/sweep_region.vert takes).
    pub(crate) fn ndc(&self, size: [u32; 2]) -> [[f32; 2]; 8] {
        self.vertices.map(|[x, y]| {
            [
                x / size[0] as f32 * 2.0 - 1.0,
                y / size[1] as f32 * 2.0 - 1.0,
            ]
        })
    }

    /// Whether a point lies inside (or on the edge, within `eps` for the rounding of
    /// the cut's vertices).
    #[cfg(test)]
    pub(crate) fn contains(&self, x: f32, y: f32, eps: f32) -> bool {
        let [x0, y0, x1, y1] = self.rect;
        let [s0, s1, d0, d1] = self.diagonals;
        let within = |v: f32, lo: f32, hi: f32| v >= lo - eps && v <= hi + eps;
        within(x, x0, x1) && within(y, y0, y1) && within(x + y, s0, s1) && within(x - y, d0, d1)
    }

    /// Its area in square pixels (the shoelace formula).
    pub(crate) fn area(&self) -> f64 {
        let v = self.vertices;
        let twice: f64 = (0..8)
            .map(|k| {
                let [a, b] = [v[k], v[(k + 1) % 8]];
                a[0] as f64 * b[1] as f64 - b[0] as f64 * a[1] as f64
            })
            .sum();
        twice.abs() * 0.5
    }
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

    fn regions(camera: &Camera, half: Vec3, spacing: f32, side: u32) -> (PlaneRegions, Planes) {
        let planes = Planes::for_box(camera, half, spacing).unwrap();
        let (_, view_to_tex) = view_matrices(camera, half);
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let r = plane_regions(view_to_tex, &planes, 0.01, tan_half, 1.0, [side, side]);
        (r, planes)
    }

    /// Every point of the box at or before plane i's depth projects inside plane i's
    /// rectangle and its polygon (sampled densely, independently of the vertex
    /// construction), both only grow, and the polygons cut the rectangles' corners
    /// where the box is seen obliquely.
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
            let (r, planes) = regions(&camera, half, 0.05, side);
            let areas = &r.rects;
            let polygons = &r.polygons;
            let (eye, forward, right, up) = camera.frame();
            let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
            let n = 24;
            for i in 0..planes.count as usize {
                let a = areas[i];
                if i > 0 {
                    let b = areas[i - 1];
                    assert!(a.x <= b.x && a.y <= b.y, "plane {i} shrank");
                    assert!(a.x + a.width >= b.x + b.width && a.y + a.height >= b.y + b.height);
                    // Convex polygons: the smaller inside the larger iff its vertices are.
                    for [x, y] in polygons[i - 1].vertices {
                        assert!(
                            polygons[i].contains(x, y, 1e-3),
                            "plane {i}'s polygon shrank: ({x}, {y}) not in {:?} (before {:?})",
                            polygons[i],
                            polygons[i - 1]
                        );
                    }
                }
                for [x, y] in polygons[i].vertices {
                    let inside = |v: f32, lo: u32, len: u32| {
                        v >= lo as f32 - 1e-3 && v <= (lo + len) as f32 + 1e-3
                    };
                    assert!(inside(x, a.x, a.width) && inside(y, a.y, a.height), "{a:?}");
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
                    // The polygon, by at least the margin in every direction (a pixel
                    // whose centre is within MARGIN_PX of the box's projection is drawn).
                    let r = std::f32::consts::FRAC_1_SQRT_2;
                    for (dx, dy) in [(1.0, 0.0), (0.0, 1.0), (r, r), (r, -r)] {
                        for sign in [-1.0, 1.0] {
                            let (px, py) = (x + sign * dx * MARGIN_PX, y + sign * dy * MARGIN_PX);
                            let on_screen = (0.0..=s).contains(&px) && (0.0..=s).contains(&py);
                            assert!(
                                !on_screen || polygons[i].contains(px, py, 0.0),
                                "az {az} el {el} plane {i}: ({px}, {py}) outside the polygon"
                            );
                        }
                    }
                }
            }
            // The last plane's rectangle is the whole box's, which a box seen from 4
            // away does not fill the screen with.
            let last = areas.last().unwrap();
            assert!((last.width * last.height) < side * side, "{last:?}");
            assert!(r.polygon_fraction <= r.rect_fraction + 1e-9);
            if (az, el) == (35.0, 40.0) {
                // A box seen from above a corner: its outline is a hexagon whose
                // bounding rectangle's corners the diagonals cut.
                assert!(
                    r.polygon_fraction < 0.95 * r.rect_fraction,
                    "{} against {}",
                    r.polygon_fraction,
                    r.rect_fraction
                );
            }
        }
    }

    /// A polygon's shape and area, worked by hand: the square 0..10 cut at x + y ≥ 4
    /// (a corner triangle of area 8) and x − y ≤ 20 (nothing: beyond the corner).
    #[test]
    fn a_cut_square_has_the_area_and_vertices_of_geometry() {
        let area = Area {
            x: 0,
            y: 0,
            width: 10,
            height: 10,
        };
        let p = RegionPolygon::new(area, Some([4.0, 100.0, -100.0, 20.0]));
        assert!((p.area() - 92.0).abs() < 1e-9, "{}", p.area());
        assert!(p.contains(2.0, 2.0, 0.0) && !p.contains(1.0, 1.0, 0.0));
        assert!(p.vertices.contains(&[4.0, 0.0]) && p.vertices.contains(&[0.0, 4.0]));
        // A cut beyond the far corner (a box projected off the screen) leaves nothing.
        assert_eq!(
            RegionPolygon::new(area, Some([30.0, 40.0, -100.0, 100.0])).area(),
            0.0
        );
        let whole = RegionPolygon::new(area, None);
        assert_eq!(whole.area(), 100.0);
        // Pixel (0, 0)'s centre maps to the NDC of a 10-pixel viewport's first pixel.
        assert_eq!(whole.ndc([10, 10])[0], [-1.0, -1.0]);
    }
}

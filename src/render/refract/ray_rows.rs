//! The light rays each plane moves and deposits (the forward transport on the fragment path
//! with grouped sprites, under the `rays` lever; docs/NOTES.md "Rays not yet needed").
//!
//! The light-ray grid covers every point any plane's view could need light from (traced
//! back along the light: `params::light_grid`), so on each plane most of its rays lie
//! outside the view, and many have not met the box yet: on the demo at 256², 12 % of the
//! rays were on screen at plane 0 and 58 % at the last. A ray that has neither entered
//! the box nor come onto the screen has crossed empty space on a
//! straight line from its launch, carrying its launch flux: its state on any plane is
//! known without moving it there. So plane k moves only the grid rows that have been
//! needed by then, widened by a margin, and a row joins on the first plane it is needed,
//! stepping straight from the launch plane to the previous plane in one go
//! (glsl/sweep_plane.glsl, `light_ray_plane`).
//!
//! A row is needed at plane k when one of its rays, moved straight, lies
//! - within the box (widened by [`REACH_STEPS`] reference steps: the step's probes read that
//!   far ahead) anywhere along its step from plane k − 1 to plane k; or
//! - on the screen, widened by the widest deposit a ray makes: each plane's irradiance stays
//!   whole on the screen (what the next plane's viewing rays read lies within it, and so
//!   does what `--dump light-colour` shows; the region's rectangle alone left a dumped
//!   plane's power 2.7 % short where the box is smaller than the view, tests/caustics.rs).
//!
//! Rows only join: once needed, a row is moved on every later plane, so nothing a ray did
//! is ever forgotten. Rows are whole rows of the grid (all columns).
//!
//! What is not exact: softness diffuses flux between neighbouring rays (`diffuse_flux`), so
//! a shadow's penumbra spreads across rows a little every plane, also into rows not moved
//! yet, which keep the launch flux. The moved rows reach [`SOFT_MARGIN_SIGMAS`] standard
//! deviations of that spread (and a stride) beyond the needed ones, where what the
//! penumbra's Gaussian tail would have carried is below 3e-7 of its contrast. Without
//! softness the only difference is rounding: a joining ray steps to its plane in one
//! straight step instead of plane by plane (the same kind of difference as the `clear`
//! lever's one sub-step).

use glam::{Mat4, Vec2, Vec3};

use super::region::{BoxEdges, REACH_STEPS};
use super::Planes;

/// Standard deviations of the softness' spread that the moved rows reach beyond the
/// needed ones: a Gaussian's tail beyond 5 sigma holds 2.9e-7 of it.
pub(crate) const SOFT_MARGIN_SIGMAS: f32 = 5.0;

/// One plane's rows of the light-ray grid, [lo, end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Rows {
    pub(crate) lo: u32,
    pub(crate) end: u32,
}

impl Rows {
    fn hull(self, other: Rows) -> Rows {
        if self.end <= self.lo {
            return other;
        }
        if other.end <= other.lo {
            return self;
        }
        Rows {
            lo: self.lo.min(other.lo),
            end: self.end.max(other.end),
        }
    }

    fn widened(self, by: u32, rows: u32) -> Rows {
        Rows {
            lo: self.lo.saturating_sub(by),
            end: (self.end + by).min(rows),
        }
    }
}

/// What the light rays' grid looks like: its corner and cell on the launch plane (view
/// units), its columns and rows, and the light's travel direction in view space.
pub(crate) struct RayGrid {
    pub(crate) grid: [f32; 4],
    pub(crate) dims: [u32; 2],
    pub(crate) light: Vec3,
}

/// The camera and planes the rows are found for.
pub(crate) struct View<'a> {
    pub(crate) view_to_tex: Mat4,
    pub(crate) planes: &'a Planes,
    pub(crate) ref_step: f32,
    pub(crate) tan_half: f32,
    pub(crate) size: [u32; 2],
}

/// One plane's share of the light rays: the workgroups of `light_splat_groups.comp` that
/// make deposits, [lo, end) (each SPLAT_GROUP_WORKGROUP groups of 2 x 2 rays, in the grid's
/// row order), the grid rows the light pass moves (all the rays those groups read,
/// and more), and the grid rows needed by then, which the compute path deposits (its
/// deposits go by rows of the grid, not by groups; `moved` holds them and a neighbour
/// row either side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PlaneRays {
    pub(crate) workgroups: Rows,
    pub(crate) moved: Rows,
    pub(crate) needed: Rows,
}

/// How many texel rows of the ray images hold the grid's rays (in row order, each texel
/// row `ray_image[0]` rays).
pub(crate) fn ray_texel_rows(grid: [u32; 2], ray_image: [u32; 2]) -> u32 {
    (grid[0] * grid[1])
        .div_ceil(ray_image[0])
        .clamp(1, ray_image[1])
}

/// The texel rows of the ray images (each `ray_image[0]` texels wide, the grid's rays in
/// row order) that plane `i`'s light pass moves, [lo, end), and those the previous plane
/// moved (a row outside them still holds its launch state: the pass steps it from the
/// launch plane first): those of the planes' moved grid rows, or every row that holds
/// rays when `plane_rays` is None (`rays=all`). Both paths' light passes.
pub(crate) fn light_pass_rows(
    plane_rays: Option<&[PlaneRays]>,
    i: u32,
    grid: [u32; 2],
    ray_image: [u32; 2],
) -> ((u32, u32), (u32, u32)) {
    let rows = ray_texel_rows(grid, ray_image);
    let texel_rows = |r: Rows| {
        let lo = r.lo * grid[0] / ray_image[0];
        let end = (r.end * grid[0]).div_ceil(ray_image[0]).clamp(lo, rows);
        (lo, end)
    };
    match plane_rays {
        Some(p) => (
            texel_rows(p[i as usize].moved),
            match i {
                0 => (0, 0),
                _ => texel_rows(p[i as usize - 1].moved),
            },
        ),
        None => ((0, rows), (0, rows)),
    }
}

/// Per plane, both only growing. `deposit_px` is how far a ray's deposit reaches from it
/// (pixels); `diffusion` the softness' weight and stride (params::diffusion);
/// `group_workgroup` the groups per workgroup.
pub(crate) fn light_ray_rows(
    view: &View,
    rays: &RayGrid,
    deposit_px: f32,
    diffusion: (f32, u32),
    group_workgroup: u32,
) -> Vec<PlaneRays> {
    let planes = view.planes;
    let box_edges = BoxEdges::new(view.view_to_tex);
    let reach = REACH_STEPS * view.ref_step;
    let launch = planes.first_depth - planes.spacing;
    let slope = Vec2::new(rays.light.x, rays.light.y) / rays.light.z;
    let h = view.size[1] as f32;
    let [columns, rows] = rays.dims;
    let group_columns = columns.div_ceil(2);
    let groups = group_columns * rows.div_ceil(2);
    let empty = Rows { lo: 0, end: 0 };
    // The grid rows whose rays, moved straight to depth z, have y in [y0, y1].
    let rows_at = |z: f32, y0: f32, y1: f32| -> Rows {
        let c = rays.grid[1] + slope.y * (z - launch);
        let cell = rays.grid[3];
        let a = ((y0 - c) / cell - 0.5).floor();
        let b = ((y1 - c) / cell - 0.5).ceil();
        if !(b >= 0.0 && a < rows as f32) {
            return empty;
        }
        Rows {
            lo: a.max(0.0) as u32,
            end: (b + 1.0).min(rows as f32) as u32,
        }
    };
    let (w_soft, stride) = diffusion;
    let mut needed = empty;
    let mut out = Vec::with_capacity(planes.count as usize);
    for k in 0..planes.count {
        let z = planes.depth(k);
        let z_prev = z - planes.spacing;
        // The box along the step, widened by the probes' reach.
        let points = box_edges.slab_points(z_prev - reach, z + reach);
        if !points.is_empty() {
            let y0 = points.iter().map(|p| p.y).fold(f32::INFINITY, f32::min) - reach;
            let y1 = points.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max) + reach;
            needed = needed
                .hull(rows_at(z_prev, y0, y1))
                .hull(rows_at(z, y0, y1));
        }
        // The screen, widened by the widest deposit, in view units at this depth (pixel y
        // runs down).
        let to_y = |py: f32| -(py / h * 2.0 - 1.0) * z * view.tan_half;
        let y_top = to_y(-deposit_px);
        let y_bottom = to_y(h + deposit_px);
        needed = needed.hull(rows_at(z, y_bottom, y_top));
        if needed.end <= needed.lo {
            out.push(PlaneRays {
                workgroups: empty,
                moved: empty,
                needed: empty,
            });
            continue;
        }
        // The workgroups whose groups hold the needed rows, and the rows those groups
        // span, with a neighbour row either side (a deposit reads its neighbours).
        let first_group = needed.lo / 2 * group_columns;
        let end_group = (needed.end.div_ceil(2) * group_columns).min(groups);
        let workgroups = Rows {
            lo: first_group / group_workgroup,
            end: end_group.div_ceil(group_workgroup),
        };
        let read = Rows {
            lo: 2 * (workgroups.lo * group_workgroup / group_columns),
            end: 2 * (workgroups.end * group_workgroup).div_ceil(group_columns),
        }
        .widened(1, rows);
        let sigma = stride as f32 * (2.0 * w_soft * (k + 1) as f32).sqrt();
        let margin = 1 + stride + (SOFT_MARGIN_SIGMAS * sigma).ceil() as u32;
        out.push(PlaneRays {
            workgroups,
            moved: read.widened(margin, rows),
            needed,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::refract::params::light_grid;
    use crate::render::refract::region::view_matrices;
    use crate::render::Camera;

    /// Every ray that a straight path puts inside the box at a plane's depth, or onto the
    /// screen, is in a moved row on that plane and every later one;
    /// its group's workgroup deposits there; the moved rows hold the rows of every
    /// deposited group and a neighbour row either side. Checked ray by ray, independently
    /// of the slab construction, for oblique, grazing and overhead light and views.
    #[test]
    fn every_ray_the_view_or_the_box_needs_is_moved() {
        let half = Vec3::new(0.5, 0.3, 0.4);
        let side = 48u32;
        let ref_step = 0.02;
        for (az, el, light) in [
            (35.0, 40.0, Vec3::new(0.3, -0.8, 0.5)),
            (-60.0, 4.0, Vec3::new(-0.5, -0.5, 0.7)),
            (120.0, -30.0, Vec3::new(0.1, 0.2, 1.0)),
            (10.0, 80.0, Vec3::new(0.0, -0.9, 0.45)),
        ] {
            let camera = Camera {
                azimuth: az,
                elevation: el,
                distance: 1.6,
                ..Default::default()
            };
            let planes = Planes::for_box(&camera, half, 0.03).unwrap();
            let (_, view_to_tex) = view_matrices(&camera, half);
            let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
            let size = [side, side];
            let light = light.normalize();
            let (grid, dims) = light_grid(&planes, light, tan_half, 1.0, size, 1.0, 4 * 48 * 48);
            let view = View {
                view_to_tex,
                planes: &planes,
                ref_step,
                tan_half,
                size,
            };
            let rays = RayGrid { grid, dims, light };
            let wg = 8;
            let out = light_ray_rows(&view, &rays, 3.0, (0.0, 1), wg);
            let launch = planes.first_depth - planes.spacing;
            let slope = Vec2::new(light.x, light.y) / light.z;
            let group_columns = dims[0].div_ceil(2);
            let mut needed_any = 0;
            for k in 0..planes.count as usize {
                if k > 0 {
                    let (a, b) = (out[k - 1], out[k]);
                    for (x, y) in [
                        (a.moved, b.moved),
                        (a.workgroups, b.workgroups),
                        (a.needed, b.needed),
                    ] {
                        if x.end > x.lo {
                            assert!(y.lo <= x.lo && y.end >= x.end, "plane {k}: shrank");
                        }
                    }
                }
                // The needed rows' deposits read a neighbour row either side: moved.
                let (n, m) = (out[k].needed, out[k].moved);
                if n.end > n.lo {
                    assert!(
                        m.lo <= n.lo.saturating_sub(1) && m.end >= (n.end + 1).min(dims[1]),
                        "plane {k}: needed {n:?}, moved {m:?}"
                    );
                }
                let w = out[k].workgroups;
                if w.end > w.lo {
                    // The rows of the deposited groups, and their neighbours, are moved.
                    let first_row = 2 * (w.lo * wg / group_columns);
                    let last_row = (2 * ((w.end * wg - 1) / group_columns) + 1).min(dims[1] - 1);
                    let m = out[k].moved;
                    assert!(
                        m.lo <= first_row.saturating_sub(1),
                        "plane {k}: {m:?} {w:?}"
                    );
                    assert!(
                        m.end >= (last_row + 2).min(dims[1]),
                        "plane {k}: {m:?} {w:?}"
                    );
                }
                let z = planes.depth(k as u32);
                for j in 0..dims[1] {
                    for i in (0..dims[0]).step_by(3) {
                        let at = |z: f32| {
                            let p = Vec2::new(grid[0], grid[1])
                                + (Vec2::new(i as f32, j as f32) + 0.5)
                                    * Vec2::new(grid[2], grid[3])
                                + slope * (z - launch);
                            p.extend(z)
                        };
                        let in_box = [at(z), at(z - planes.spacing)].into_iter().any(|p| {
                            let t = view_to_tex.transform_point3(p);
                            t.cmpge(Vec3::ZERO).all() && t.cmple(Vec3::ONE).all()
                        });
                        let p = at(z);
                        let px = (p.x / (z * tan_half) * 0.5 + 0.5) * side as f32;
                        let py = (-p.y / (z * tan_half) * 0.5 + 0.5) * side as f32;
                        let s = side as f32;
                        let in_view = px >= 0.0 && px <= s && py >= 0.0 && py <= s;
                        if !(in_box || in_view) {
                            continue;
                        }
                        needed_any += 1;
                        for later in &out[k..] {
                            // The compute path deposits the needed rows.
                            let n = later.needed;
                            assert!(
                                j >= n.lo && j < n.end,
                                "plane {k}: ray ({i}, {j}) needed, needed rows {n:?}"
                            );
                            let m = later.moved;
                            assert!(
                                j >= m.lo && j < m.end,
                                "az {az} el {el} plane {k}: ray ({i}, {j}) needed (box \
                                 {in_box}, view {in_view}), moved rows {m:?}"
                            );
                            let g = (j / 2) * group_columns + i / 2;
                            let w = later.workgroups;
                            assert!(
                                g / wg >= w.lo && g / wg < w.end,
                                "plane {k}: ray ({i}, {j}) in group {g}, workgroups {w:?}"
                            );
                        }
                    }
                }
            }
            assert!(
                needed_any > 100,
                "az {az} el {el}: {needed_any} needed rays checked"
            );
            // Something is saved: not every row is moved on the first plane.
            let first = out.iter().find(|p| p.moved.end > p.moved.lo).unwrap();
            eprintln!(
                "az {az} el {el}: first moved {:?} of {} rows",
                first.moved, dims[1]
            );
        }
    }
}

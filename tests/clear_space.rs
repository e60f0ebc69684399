//! Issue 31, "finished rays cost nothing" for the light: the `clear` lever steps a forward
//! light ray to the next plane in one Snell sub-step instead of four where every value the
//! step can meet is the same, or clear with one η (render::value_ranges). Checked here:
//! the ranges bound what a sample can read (against a CPU evaluation of their definition),
//! and rays through a lens, lit obliquely so that they cross the bricks' sides on the
//! diagonal, leave it where the four sub-steps put them.

mod common;

use common::{ball_at, face_on, glass, sweep, with_context};
use glam::Vec3;
use refrakt::render::limits::VALUE_BRICK;
use refrakt::render::Light;
use refrakt::render::{Frame, Planes, RenderOptions, StateBuffer, SweepOptions};

/// A volume whose sides are not multiples of the brick: each brick's range is the min and
/// max over its voxels and a one-voxel apron (clamped to the volume), the dilated range
/// the min and max over the 3 × 3 × 3 bricks around it (clamped to the grid).
#[test]
fn value_ranges_bound_every_sample_of_their_bricks() {
    with_context(|ctx| {
        let dims = [13u32, 9, 6];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let mut seed = 777u32;
        let mut values: Vec<f32> = (0..n)
            .map(|_| {
                seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
                (seed >> 8) as f32 / (1u32 << 24) as f32
            })
            .collect();
        // A constant block, so that some ranges are a single value.
        for z in 0..dims[2] as usize {
            for y in 0..dims[1] as usize {
                for x in 6..dims[0] as usize {
                    values[x + dims[0] as usize * (y + dims[1] as usize * z)] = 0.25;
                }
            }
        }
        let mut volume = refrakt::volume::Volume::new(
            dims,
            [1.0, 1.0, 1.0],
            refrakt::volume::Voxels::F32(values.clone()),
        )
        .unwrap();
        volume.range = Some((0.0, 1.0));
        let tf = glass(1.5);
        let mut renderer = refrakt::render::Renderer::new(ctx, &volume, &tf).unwrap();
        let cam = refrakt::render::Camera::default();
        let mut opts = RenderOptions {
            width: 8,
            height: 8,
            ..Default::default()
        };
        opts.lights = vec![Light::for_camera(&cam)];
        renderer
            .render(refrakt::render::Model::Refract, &cam, &opts)
            .unwrap();
        let [bricks, dilated] = renderer.read_value_ranges().unwrap().expect("built");
        let b = VALUE_BRICK as i32;
        let grid = dims.map(|d| d.div_ceil(VALUE_BRICK) as i32);
        assert_eq!(bricks.len(), (grid[0] * grid[1] * grid[2]) as usize);
        let at = |x: i32, y: i32, z: i32| {
            let c = |v: i32, k: usize| v.clamp(0, dims[k] as i32 - 1) as usize;
            values[c(x, 0) + dims[0] as usize * (c(y, 1) + dims[1] as usize * c(z, 2))]
        };
        let index = |x: i32, y: i32, z: i32| (x + grid[0] * (y + grid[1] * z)) as usize;
        let mut own = vec![[0.0f32; 2]; bricks.len()];
        let mut single = 0;
        for bz in 0..grid[2] {
            for by in 0..grid[1] {
                for bx in 0..grid[0] {
                    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
                    for z in bz * b - 1..=bz * b + b {
                        for y in by * b - 1..=by * b + b {
                            for x in bx * b - 1..=bx * b + b {
                                lo = lo.min(at(x, y, z));
                                hi = hi.max(at(x, y, z));
                            }
                        }
                    }
                    let got = bricks[index(bx, by, bz)];
                    assert_eq!(got, [lo, hi], "brick {bx},{by},{bz}");
                    own[index(bx, by, bz)] = [lo, hi];
                    single += (lo == hi) as usize;
                }
            }
        }
        assert!(single > 0, "the constant block gives single-value bricks");
        for bz in 0..grid[2] {
            for by in 0..grid[1] {
                for bx in 0..grid[0] {
                    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
                    for dz in -1..=1 {
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                let c = |v: i32, k: usize| v.clamp(0, grid[k] - 1);
                                let r = own[index(c(bx + dx, 0), c(by + dy, 1), c(bz + dz, 2))];
                                lo = lo.min(r[0]);
                                hi = hi.max(r[1]);
                            }
                        }
                    }
                    assert_eq!(
                        dilated[index(bx, by, bz)],
                        [lo, hi],
                        "dilated {bx},{by},{bz}"
                    );
                }
            }
        }
    });
}

/// The light rays of a forward-transport frame at `plane`: (flux, position on the plane,
/// v = η dx/ds), in grid order.
fn rays(f: &Frame, plane: u32) -> Vec<(Vec3, glam::Vec2, Vec3)> {
    let stats = f.sweep.as_ref().unwrap();
    let count = (stats.light_rays[0] * stats.light_rays[1]) as usize;
    let dump = |buffer| {
        &f.dumps
            .iter()
            .find(|d| d.buffer == buffer && d.plane == plane)
            .unwrap()
            .pixels
    };
    let (flux, dirs) = (
        dump(StateBuffer::LightRays),
        dump(StateBuffer::LightRayDirections),
    );
    flux.iter()
        .zip(dirs)
        .take(count)
        .map(|(a, d)| {
            (
                Vec3::new(a[0], a[1], a[2]),
                glam::Vec2::new(a[3], d[3]),
                Vec3::new(d[0], d[1], d[2]),
            )
        })
        .collect()
}

/// A ball lens (η 1.5) off the volume's centre, lit 25° off the view axis so that the
/// rays cross the bricks' sides on the diagonal: behind it, with and without the clear
/// step, every ray that carries light in both and that the lens turned by less than 0.6
/// rad is where the four sub-steps put it (within 0.1 voxels) and travels the same way
/// (within 2 mrad), at sample distances 1 and 0.5. The single step rounds differently, and
/// η looked up through the filtered transfer-function texture (8-bit sub-texel weights)
/// turns a ray by steps of ~1 mrad (2^-10 measured) for a rounding's change of position.
/// A refraction skipped at a brick's side would turn a ray by the lens' deflection, tens
/// of mrad (checked: many rays are turned).
#[test]
fn clear_space_keeps_every_ray_through_an_oblique_lens() {
    with_context(|ctx| {
        let n = 64u32;
        let vox = 1.0 / n as f32;
        let r = 0.2;
        let vol = ball_at(n, r, [0.07, -0.04, 0.03]);
        let tf = glass(1.5);
        let cam = face_on(2.0, 24.0);
        let view = (cam.eye() - cam.target).normalize();
        let side = view.cross(Vec3::Y).normalize();
        let (s, c) = 25f32.to_radians().sin_cos();
        let light = Light {
            source: refrakt::light::LightSource::Directional {
                towards: (view * c + side * s).normalize(),
            },
            colour: [1.0; 3],
            softness: 0.0,
        };
        for sd in [1.0f32, 0.5] {
            let planes = Planes::for_box(&cam, Vec3::splat(0.5), sd * vox).unwrap();
            let behind =
                ((cam.distance + 0.35 - planes.first_depth) / planes.spacing).ceil() as u32;
            let frame = |clear: bool| {
                let mut opts = RenderOptions {
                    width: 64,
                    height: 64,
                    sample_distance: sd,
                    ..Default::default()
                };
                opts.lights = vec![light];
                opts.sweep = SweepOptions {
                    dumps: vec![
                        (StateBuffer::LightRays, behind),
                        (StateBuffer::LightRayDirections, behind),
                    ],
                    ..Default::default()
                };
                opts.sweep.levers.clear = clear;
                rays(&sweep(ctx, &vol, &tf, &cam, &opts), behind)
            };
            let (four, one) = (frame(false), frame(true));
            assert_eq!(four.len(), one.len());
            // The way unturned light travels: the most common direction.
            let straight = four
                .iter()
                .filter(|r| r.0.x > 0.0)
                .map(|r| r.2.normalize())
                .fold(Vec3::ZERO, |a, d| a + d)
                .normalize();
            let (mut both, mut turned, mut only_one, mut far) = (0usize, 0usize, 0usize, 0usize);
            let (mut worst_pos, mut worst_angle) = (0.0f32, 0.0f32);
            for (a, b) in four.iter().zip(&one) {
                match (a.0.x > 0.0, b.0.x > 0.0) {
                    (true, true) => {}
                    (false, false) => continue,
                    _ => {
                        only_one += 1;
                        continue;
                    }
                }
                both += 1;
                let (da, db) = (a.2.normalize(), b.2.normalize());
                // Rays the lens turned far (its rim, near the critical angle at the exit,
                // or past 35°, where a plane step moves them up to ten voxels sideways)
                // are ill-conditioned: there float rounding alone moves them (measured up
                // to 0.7 voxels at 90° of deflection).
                if da.angle_between(straight) > 0.6 || db.angle_between(straight) > 0.6 {
                    far += 1;
                    continue;
                }
                if da.angle_between(straight) > 0.05 {
                    turned += 1;
                }
                worst_pos = worst_pos.max((a.1 - b.1).length() / vox);
                worst_angle = worst_angle.max(da.angle_between(db));
                assert!(
                    (a.0.x - b.0.x).abs() <= 1e-4 * a.0.x.max(1e-3),
                    "sd {sd}: flux {} vs {}",
                    a.0.x,
                    b.0.x
                );
            }
            println!(
                "sd {sd}: {both} rays carry light in both ({turned} turned 0.05-0.6 rad by the lens, \
                 {far} further; {only_one} in one only); worst position {worst_pos:.2e} voxels, \
                 direction {worst_angle:.2e} rad"
            );
            assert!(
                both > 1000 && turned > 100,
                "sd {sd}: {both} rays, {turned} turned"
            );
            assert!(
                only_one * 200 <= both,
                "sd {sd}: {only_one} rays lit in one only"
            );
            assert!(worst_pos <= 0.1, "sd {sd}: a ray moved {worst_pos} voxels");
            assert!(
                worst_angle <= 2e-3,
                "sd {sd}: a ray turned {worst_angle} rad"
            );
        }
    });
}

//! Issue 5: refraction geometry of the viewing rays. A thick glass slab tilted by a known
//! angle shifts every ray sideways by t·sin(θ − θ')/cos θ' and leaves its direction
//! unchanged (Snell's law at two parallel faces). The reference is traced on the CPU with
//! Snell's law per pixel, for the camera's exact perspective rays.

mod common;

use common::*;
use glam::Vec3;
use refrakt::render::{Light, Model, RenderOptions, Renderer, StateBuffer, SweepOptions};
use refrakt::transfer::{Piecewise, TransferFunctions};
use refrakt::volume::{Volume, Voxels};

/// Snell refraction of unit direction `d` at a surface with unit normal `n` facing the
/// incoming ray, from index `n1` into `n2`.
fn refract(d: Vec3, n: Vec3, n1: f32, n2: f32) -> Vec3 {
    let r = n1 / n2;
    let c = -n.dot(d);
    let k = 1.0 - r * r * (1.0 - c * c);
    assert!(k > 0.0, "the test geometry must not reflect totally");
    r * d + (r * c - k.sqrt()) * n
}

/// Where the ray (o, d) reaches view depth `depth` (distance along the camera's axis).
fn at_depth(o: Vec3, d: Vec3, eye: Vec3, fwd: Vec3, depth: f32) -> Vec3 {
    let t = (depth - (o - eye).dot(fwd)) / d.dot(fwd);
    o + t * d
}

struct Slab {
    /// Tilt of the slab normal from the view axis, degrees.
    tilt: f32,
    /// Thickness in world units (the volume is the unit cube).
    thickness: f32,
    eta: f32,
}

impl Slab {
    fn normal(&self) -> Vec3 {
        let a = self.tilt.to_radians();
        Vec3::new(a.sin(), 0.0, a.cos())
    }

    /// Glass (value 1) between the faces, air (0) outside, with a linear ramp `ramp`
    /// voxels wide centred on each face: a band-limited interface, as a scanner records
    /// one (partial-volume effect), which trilinear reconstruction resolves into flat
    /// iso-surfaces.
    /// The voxel value at signed distance `u` from the slab's mid-plane (along its normal).
    fn value(&self, u: f32, ramp_width: f32) -> f32 {
        0.5 + 0.5 * ((0.5 * self.thickness - u.abs()) / ramp_width).tanh()
    }

    fn volume(&self, n: u32, ramp: f32) -> Volume {
        let nrm = self.normal();
        let vox = 1.0 / n as f32;
        let mut v = Vec::with_capacity((n * n * n) as usize);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) * vox + Vec3::splat(0.5 * vox)
                        - Vec3::splat(0.5);
                    v.push(self.value(p.dot(nrm), ramp * vox));
                }
            }
        }
        let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(v)).unwrap();
        vol.range = Some((0.0, 1.0));
        vol
    }

    /// Snell's lateral shift for incidence angle θ on the slab.
    fn snell_shift(&self, theta: f32) -> f32 {
        let theta_t = (theta.sin() / self.eta).asin();
        self.thickness * (theta - theta_t).sin() / theta_t.cos()
    }

    /// Exact lateral shift, along the slab, of a ray crossing the stratified medium
    /// eta(u) = 1 + (eta − 1)·value(u): eta·sin θ is invariant (Snell in the continuous
    /// limit), so the ray advances tan θ(u) per unit of u instead of tan θ0.
    fn graded_shift(&self, theta0: f32, ramp_width: f32) -> f64 {
        let s0 = theta0.sin() as f64;
        let tan = |sin: f64| sin / (1.0 - sin * sin).sqrt();
        let steps = 50_000;
        let du = 1.0 / steps as f64;
        (0..steps)
            .map(|i| {
                let u = -0.5 + (i as f64 + 0.5) * du;
                let eta = 1.0 + (self.eta as f64 - 1.0) * self.value(u as f32, ramp_width) as f64;
                (tan(s0 / eta) - tan(s0)) * du
            })
            .sum()
    }

    /// The ray (eye, d) traced through both faces; returns its point at view depth `depth`.
    fn trace(&self, eye: Vec3, d: Vec3, fwd: Vec3, depth: f32) -> Vec3 {
        let n = self.normal();
        let h = 0.5 * self.thickness;
        let t1 = (h - eye.dot(n)) / d.dot(n);
        let p1 = eye + t1 * d;
        let d1 = refract(d, n, 1.0, self.eta);
        let t2 = (-h - p1.dot(n)) / d1.dot(n);
        let p2 = p1 + t2 * d1;
        let d2 = refract(d1, n, self.eta, 1.0);
        at_depth(p2, d2, eye, fwd, depth)
    }
}

/// Options for a `size` image at sample distance `sd`, lit by hard white light from the
/// camera's side, with `dumps`.
fn lit_from_the_camera(
    cam: &refrakt::render::Camera,
    size: [u32; 2],
    sd: f32,
    dumps: Vec<(StateBuffer, u32)>,
) -> RenderOptions {
    let mut opts = RenderOptions {
        width: size[0],
        height: size[1],
        sample_distance: sd,
        ..Default::default()
    };
    opts.sweep = SweepOptions {
        dumps,
        ..Default::default()
    };
    opts.lights = vec![Light {
        source: refrakt::light::LightSource::Directional {
            towards: cam.eye().normalize(),
        },
        colour: [1.0; 3],
        softness: 0.0,
    }];
    opts
}

/// Relative per-pixel errors of the measured ray positions behind the slab.
struct Errors {
    /// Against the exact shift for the graded interface the volume holds.
    graded: Vec<f32>,
    /// Against Snell's closed form for sharp faces.
    snell: Vec<f32>,
}

fn worst(e: &[f32]) -> f32 {
    e.iter().cloned().fold(0.0, f32::max)
}

fn mean(e: &[f32]) -> f32 {
    e.iter().sum::<f32>() / e.len() as f32
}

/// Renders the slab (`n`³ voxels, faces `ramp` voxels wide) face-on and compares where the
/// viewing rays of the central 16 × 16 pixels are on two planes behind it.
fn measure(ctx: &refrakt::vk::Context, slab: &Slab, n: u32, ramp: f32) -> Errors {
    let vol = slab.volume(n, ramp);
    let tf = TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [slab.eta])]),
        ..Default::default()
    };
    // Narrow field of view from afar: rays nearly parallel, all crossing both faces inside
    // the volume.
    let cam = face_on(4.0, 8.0);
    let (w, h) = (32u32, 32u32);
    let (eye, fwd, right, up) = cam.frame();
    let sd = 0.5;
    let planes = refrakt::render::Planes::for_box(&cam, Vec3::splat(0.5), sd / n as f32).unwrap();
    // Behind the slab (its back face reaches z ≈ −0.24 within the patch read): two planes
    // 0.1 apart, so an error in the exit direction shows as well as one in the offset.
    let behind = [0.36f32, 0.46]
        .map(|z| ((cam.distance + z - planes.first_depth) / planes.spacing).ceil() as u32);
    let dumps = behind
        .iter()
        .map(|&p| (StateBuffer::ViewPosition, p))
        .collect();
    let opts = lit_from_the_camera(&cam, [w, h], sd, dumps);
    let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
    let f = r.render(Model::Refract, &cam, &opts).unwrap();
    let nrm = slab.normal();
    let mut errors = Errors {
        graded: Vec::new(),
        snell: Vec::new(),
    };
    for dump in &f.dumps {
        for y in 8..24 {
            for x in 8..24 {
                let q = dump.pixels[(y * w + x) as usize];
                let got = eye + q[0] * right + q[1] * up + q[2] * fwd;
                let t = (cam.fov_y.to_radians() * 0.5).tan();
                let nx = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * t;
                let ny = -((y as f32 + 0.5) / h as f32 * 2.0 - 1.0) * t;
                let d = (fwd + nx * right + ny * up).normalize();
                // The buffer holds the point on the plane the ray has just reached (one
                // spacing beyond the plane the dump is named after): use its own depth.
                let straight = at_depth(eye, d, eye, fwd, q[2]);
                let snell = slab.trace(eye, d, fwd, q[2]) - straight;
                // The exit ray is parallel to the entering one and offset along the slab
                // by dt; on a view plane that offset is dt slid along the ray.
                let theta0 = d.dot(nrm).abs().acos();
                let along = (d - d.dot(nrm) * nrm).normalize();
                let dt = along * slab.graded_shift(theta0, ramp / n as f32) as f32;
                let graded = dt - dt.dot(fwd) / d.dot(fwd) * d;
                let moved = got - straight;
                errors
                    .graded
                    .push((moved - graded).length() / graded.length());
                errors.snell.push((moved - snell).length() / snell.length());
            }
        }
    }
    errors
}

#[test]
fn tilted_slab_shifts_rays_by_snells_law() {
    with_context(|ctx| {
        let slab = Slab {
            tilt: 30.0,
            thickness: 0.3,
            eta: 1.5,
        };
        // The closed form and the CPU tracer agree with each other (0.0581 for the centre
        // ray), and the stratified-medium integral converges to them for a sharp face.
        let centre = slab.snell_shift(slab.tilt.to_radians());
        assert!((centre - 0.0581).abs() < 1e-4, "{centre}");
        let theta = slab.tilt.to_radians();
        // (The ray lags behind along the slab: a negative shift.)
        let sharp = -slab.graded_shift(theta, 1e-5) * (theta as f64).cos();
        assert!((sharp - centre as f64).abs() < 1e-4, "{sharp} vs {centre}");
        let (eye, fwd) = (Vec3::new(0.0, 0.0, 4.0), Vec3::NEG_Z);
        let traced = slab.trace(eye, fwd, fwd, 4.5) - at_depth(eye, fwd, eye, fwd, 4.5);
        assert!(
            (traced.length() - centre).abs() < 1e-4,
            "{traced} vs {centre}"
        );

        // Faces one voxel wide are the volume's picture of sharp faces (issue 13: the ray
        // turns once, by Snell's law between the plateaus, at the face's middle): within
        // 1 % of Snell per pixel (measured 0.33 % worst; issue 5 asked 5 %). The graded
        // medium the tanh ramp literally stores shifts rays 1.7 % further: within 2.5 %.
        let e = measure(ctx, &slab, 96, 1.0);
        println!(
            "1-voxel faces: per-pixel error vs Snell mean {:.4} worst {:.4}; vs graded mean {:.4} worst {:.4}",
            mean(&e.snell), worst(&e.snell), mean(&e.graded), worst(&e.graded)
        );
        assert!(worst(&e.snell) <= 0.01, "worst {}", worst(&e.snell));
        assert!(worst(&e.graded) <= 0.025, "worst {}", worst(&e.graded));

        // Faces three voxels wide shift rays 8 % more than sharp faces would (tan θ is
        // convex in η); such a ramp is a graded medium, and the renderer follows it, not
        // the sharp formula (measured worst 1.0 % from the graded shift).
        let e = measure(ctx, &slab, 64, 3.0);
        println!(
            "3-voxel faces: per-pixel error vs Snell mean {:.4}; vs graded mean {:.4} worst {:.4}",
            mean(&e.snell),
            mean(&e.graded),
            worst(&e.graded)
        );
        assert!(mean(&e.snell) > 0.05, "{}", mean(&e.snell));
        assert!(worst(&e.graded) <= 0.01, "worst {}", worst(&e.graded));
    });
}

/// Glass filling the whole volume box is a slab whose faces are the box's own: a ray
/// that enters through the front face and leaves through the back one leaves parallel
/// to its camera ray (Snell's law at two parallel faces), whatever the sample distance
/// and however the planes fall. Outside the box nothing may turn it again. (The ray
/// equation's central differences of η, taken a voxel apart from a point just outside
/// the box, reached back into it and kicked rays that had already turned at the face —
/// once or twice, as the planes fell, by up to 6°: single-pixel diagonal lines across the
/// water stand-in's tank, seen through its back face.) Oblique view, 20° and 12° off the
/// face normals; the central pixels' rays, which all leave through the back face.
#[test]
fn rays_leave_a_box_full_of_glass_parallel_to_their_camera_rays() {
    with_context(|ctx| {
        let n = 32u32;
        let mut vol = Volume::new(
            [n; 3],
            [1.0; 3],
            Voxels::F32(vec![1.0; (n * n * n) as usize]),
        )
        .unwrap();
        vol.range = Some((0.0, 1.0));
        let tf = TransferFunctions {
            eta: Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.5])]),
            ..Default::default()
        };
        let cam = refrakt::render::Camera {
            azimuth: 20.0,
            elevation: 12.0,
            distance: 4.0,
            fov_y: 8.0,
            ..Default::default()
        };
        let (w, h) = (32u32, 32u32);
        let t = (cam.fov_y.to_radians() * 0.5).tan();
        for sd in [1.0f32, 0.5] {
            let planes =
                refrakt::render::Planes::for_box(&cam, Vec3::splat(0.5), sd / n as f32).unwrap();
            let dumps = vec![(StateBuffer::ViewDirection, planes.count - 1)];
            let opts = lit_from_the_camera(&cam, [w, h], sd, dumps);
            let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
            let f = r.render(Model::Refract, &cam, &opts).unwrap();
            let (mut worst, mut sum, mut count) = (0.0f32, 0.0f32, 0);
            for y in 8..24 {
                for x in 8..24 {
                    let v = f.dumps[0].pixels[(y * w + x) as usize];
                    // View space: x right, y up, z forward.
                    let camera_ray = Vec3::new(
                        ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * t,
                        -((y as f32 + 0.5) / h as f32 * 2.0 - 1.0) * t,
                        1.0,
                    )
                    .normalize();
                    let left = Vec3::new(v[0], v[1], v[2]).normalize();
                    let angle = left.dot(camera_ray).clamp(-1.0, 1.0).acos().to_degrees();
                    // w: the value at the ray's point (the compact state), air's 0.
                    assert!(
                        v[3].abs() < 1e-3,
                        "sd {sd} pixel ({x}, {y}): the ray is still in glass (value {})",
                        v[3]
                    );
                    worst = worst.max(angle);
                    sum += angle;
                    count += 1;
                }
            }
            println!(
                "sd {sd}: angle between leaving and camera rays mean {:.4}°, worst {worst:.4}°",
                sum / count as f32
            );
            assert!(
                worst <= 0.1,
                "sd {sd}: a ray left {worst}° off its camera ray"
            );
        }
    });
}

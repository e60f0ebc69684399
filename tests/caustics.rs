//! Issue 12: the forward light transport against physics and against the CPU photon
//! tracer (src/photons.rs): power conserved through a focus, total internal reflection,
//! the paraxial focus of a ball lens at every sample distance, and the caustic of a glass
//! sphere on a floor.

mod common;

use common::floor::{annulus_mean, caustic_scene, compare_floors, measure_floor};
use common::*;
use glam::Vec3;
use refrakt::render::{
    Camera, Frame, Light, LightTransport, Planes, RenderOptions, StateBuffer, SweepOptions,
    SweepPath,
};
use refrakt::transfer::TransferFunctions;
use refrakt::vk::Context;

/// Mean of channel 0 over every pixel of a light-colour dump.
fn mean_light(f: &Frame, plane: u32) -> f64 {
    let d = f
        .dumps
        .iter()
        .find(|d| d.buffer == StateBuffer::LightColour && d.plane == plane)
        .unwrap();
    d.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / d.pixels.len() as f64
}

/// A glass ball (η 1.5, R = 19 voxels, a two-voxel surface ramp; nothing absorbs) lit
/// along the view axis focuses its light behind itself: rays cross between the marginal
/// and the paraxial focus and spread again. The mean irradiance over the viewport (the
/// power through the plane over its area) must stay that of the unobstructed light on
/// every plane — in front of the ball, inside it, through the crossing rays and beyond —
/// within 1 %, softness 0 and 1. Rim rays that physically turn back or leave the
/// frustum (the photon tracer counts them) are the only loss; the sweep must agree with
/// the tracer's power on the last planes within 1 % (it also drops rays turned further
/// than 84°, which the tracer lets land).
#[test]
fn power_is_conserved_through_a_focus() {
    with_context(|ctx| {
        let n = 48u32;
        let r = 0.4f32;
        let vol = f32_volume(n, |p| 0.5 + (r - Vec3::from(p).length()) * n as f32 / 2.0);
        let tf = glass(1.5);
        let cam = face_on(3.0, 50.0);
        let planes = Planes::for_box(&cam, Vec3::splat(0.5), 1.0 / n as f32).unwrap();
        // Both sweep paths (issue 31): the fragment path's point sprites and the compute
        // path's gather.
        for (softness, path) in [
            (0.0f32, SweepPath::Fragment),
            (1.0, SweepPath::Fragment),
            (0.0, SweepPath::Compute),
        ] {
            let mut opts = RenderOptions {
                width: 96,
                height: 96,
                ..Default::default()
            };
            opts.sweep = SweepOptions {
                light_transport: LightTransport::Forward,
                levers: refrakt::render::Levers {
                    sweep: path,
                    ..Default::default()
                },
                // Power through a plane is the sum of the flux per unit plane area (the
                // fluence, the default, weights turned rays by cos θ₀ / cos θ).
                plane_flux: true,
                dumps: (0..planes.count)
                    .map(|p| (StateBuffer::LightColour, p))
                    .collect(),
                ..Default::default()
            };
            opts.lights = vec![headlight(&cam, softness)];
            let f = sweep(ctx, &vol, &tf, &cam, &opts);
            let stats = f.sweep.as_ref().unwrap();
            println!("softness {softness}, {path:?}: clamps {:?}", stats.clamps);
            let mut worst = 0.0f64;
            let mut peak = 0.0f32;
            for p in 0..planes.count {
                let m = mean_light(&f, p);
                worst = worst.max((m - 1.0).abs());
                let d = f.dumps.iter().find(|d| d.plane == p).unwrap();
                peak = peak.max(d.pixels.iter().map(|q| q[0]).fold(0.0, f32::max));
                if p % 6 == 0 {
                    println!(
                        "softness {softness}: plane {p} depth {:.3}: mean {m:.5}",
                        planes.depth(p)
                    );
                }
            }
            println!(
                "softness {softness}: worst power error {:.3} %, brightest {peak:.1}",
                worst * 100.0
            );
            for p in [planes.count - 12, planes.count - 6, planes.count - 1] {
                let img = refrakt::photons::trace_irradiance(
                    &vol,
                    &tf,
                    &cam,
                    &opts,
                    planes.depth(p),
                    &refrakt::photons::PhotonOptions {
                        photons_per_pixel: 4,
                        plane_flux: true,
                        ..Default::default()
                    },
                    None,
                )
                .unwrap();
                let m =
                    img.pixels.iter().map(|q| q[0] as f64).sum::<f64>() / img.pixels.len() as f64;
                let ms = mean_light(&f, p);
                println!("tracer plane {p}: mean {m:.5}, sweep {ms:.5}");
                // The sweep drops rays turned beyond 84° that the tracer lets land.
                assert!(
                    (m - ms).abs() <= 0.01,
                    "plane {p}: sweep power {ms} vs photon tracer {m}"
                );
            }
            // The lens must really focus (otherwise nothing crossed).
            assert!(peak > 20.0, "no focus: brightest irradiance {peak}");
            assert!(
                worst <= 0.01,
                "softness {softness}: power off by {:.2} %",
                worst * 100.0
            );
        }
    });
}

/// Where a ray entering a perfect glass sphere (radius `r`, index `n`) parallel to the axis
/// at height `b` crosses the axis after leaving it, measured from the centre along the
/// light: Snell's law at both surfaces, exactly.
fn sphere_axis_crossing(b: f64, r: f64, n: f64) -> f64 {
    use glam::DVec2;
    // 2D: x lateral, z along the light (+z), centre at the origin.
    let refract = |d: DVec2, normal: DVec2, ratio: f64| -> DVec2 {
        // normal against d
        let c = -normal.dot(d);
        let k = 1.0 - ratio * ratio * (1.0 - c * c);
        assert!(k >= 0.0, "total internal reflection in the analytic sphere");
        ratio * d + (ratio * c - k.sqrt()) * normal
    };
    let entry = DVec2::new(b, -(r * r - b * b).sqrt());
    let d1 = refract(DVec2::new(0.0, 1.0), entry / r, 1.0 / n);
    // Second intersection with the sphere: entry + t d1, |.| = r.
    let t = -2.0 * entry.dot(d1);
    let exit = entry + t * d1;
    let d2 = refract(d1, -exit / r, n);
    // exit + u d2 crosses x = 0.
    let u = -exit.x / d2.x;
    exit.y + u * d2.y
}

/// The rays of a forward-transport frame at `plane`: launch position (from the grid),
/// position on the plane and v = η dx/ds, for rays that still carry light.
fn rays(f: &Frame, plane: u32) -> Vec<(glam::Vec2, glam::Vec2, Vec3)> {
    let stats = f.sweep.as_ref().unwrap();
    let g = stats.light_grid;
    // Ray r = j * columns + i is texel r of the dumps (row-major over the ray images).
    let (columns, count) = (
        stats.light_rays[0],
        (stats.light_rays[0] * stats.light_rays[1]) as usize,
    );
    let flux = f
        .dumps
        .iter()
        .find(|d| d.buffer == StateBuffer::LightRays && d.plane == plane)
        .unwrap();
    let dirs = f
        .dumps
        .iter()
        .find(|d| d.buffer == StateBuffer::LightRayDirections && d.plane == plane)
        .unwrap();
    let mut out = Vec::new();
    for (k, (a, d)) in flux.pixels.iter().zip(&dirs.pixels).take(count).enumerate() {
        if a[0] <= 0.0 {
            continue;
        }
        let (i, j) = ((k as u32 % columns) as f32, (k as u32 / columns) as f32);
        let launch = glam::Vec2::new(g[0] + (i + 0.5) * g[2], g[1] + (j + 0.5) * g[3]);
        out.push((
            launch,
            glam::Vec2::new(a[3], d[3]),
            Vec3::new(d[0], d[1], d[2]),
        ));
    }
    out
}

/// A ball lens (η 1.5, D = 0.5, 16-voxel radius) lit along the view axis: near-axis rays
/// (launched 2.5–5 voxels from the axis: closer than a voxel the trilinear field has no
/// lateral gradient at all) cross the axis where the photon tracer puts them in the same
/// field, and at the paraxial focus nD/(4(n−1)), each within 3 % of the focal length, at
/// sample distances 1, 0.5 and 0.25 (the thesis' backward step read 8–13 % short at the
/// finer ones).
#[test]
fn ball_lens_focus_at_every_sample_distance() {
    with_context(|ctx| {
        let n = 64u32;
        let vox = 1.0 / n as f32;
        let (eta, d) = (1.5f32, 0.5f32);
        let r = d / 2.0;
        let vol = ball(n, r);
        let tf = glass(eta);
        let cam = Camera {
            fov_y: 16.0,
            ..face_on(2.0, 16.0)
        };
        let (w, h) = (128u32, 128u32);
        let paraxial = eta * d / (4.0 * (eta - 1.0));
        for sd in [1.0f32, 0.5, 0.25] {
            let planes = Planes::for_box(&cam, Vec3::splat(0.5), sd * vox).unwrap();
            // Past the ball's back surface and its ramp.
            let behind = ((cam.distance + r + 3.0 * vox - planes.first_depth) / planes.spacing)
                .ceil() as u32;
            let depth = planes.depth(behind);
            let mut opts = frame_options(w, h, sd);
            opts.sweep = SweepOptions {
                dumps: vec![
                    (StateBuffer::LightRays, behind),
                    (StateBuffer::LightRayDirections, behind),
                ],
                ..Default::default()
            };
            opts.lights = vec![headlight(&cam, 0.0)];
            let f = sweep(ctx, &vol, &tf, &cam, &opts);
            // Each near-axis ray's axis crossing from the sweep and from the photon tracer
            // in the same field (rays the tracer sees turn back are left out of both).
            let field = refrakt::photons::Field::new(&vol, &tf, &opts).unwrap();
            let (mut sum, mut exact, mut traced, mut count) = (0.0f64, 0.0f64, 0.0f64, 0);
            for (launch, pos, v) in rays(&f, behind) {
                let b = launch.length();
                if !(2.5 * vox..=5.0 * vox).contains(&b) {
                    continue;
                }
                let rho = pos.length();
                let radial = (v.x * pos.x + v.y * pos.y) / rho;
                assert!(
                    radial < 0.0,
                    "a near-axis ray diverges after the lens (b = {b})"
                );
                let origin = Vec3::new(launch.x, launch.y, 0.6);
                let Some(e) = field
                    .trace_ray(&cam, origin, Vec3::new(0.0, 0.0, -1.0), depth, 0.1)
                    .unwrap()
                else {
                    continue;
                };
                let trho = glam::Vec2::new(e.position.x, e.position.y).length();
                let tradial = (e.direction.x * e.position.x + e.direction.y * e.position.y) / trho;
                traced += (-e.position.z + trho * -e.direction.z / -tradial) as f64;
                // Distance from the centre where the ray meets the axis.
                sum += (depth - cam.distance + rho * v.z / -radial) as f64;
                exact += sphere_axis_crossing(b as f64, r as f64, eta as f64);
                count += 1;
            }
            assert!(count > 50, "too few near-axis rays ({count})");
            let (focus, exact) = (sum / count as f64, exact / count as f64);
            let traced = traced / count as f64;
            let vs_tracer = (focus - traced).abs() / paraxial as f64;
            let vs_paraxial = (focus - paraxial as f64).abs() / paraxial as f64;
            println!(
                "sample distance {sd}: {count} rays cross the axis {focus:.4} from the centre \
                 on average; photon tracer in the same field {traced:.4} ({:.2} % of f); \
                 paraxial {paraxial:.4} ({:.2} %); Snell at a perfect sphere {exact:.4}",
                vs_tracer * 100.0,
                vs_paraxial * 100.0
            );
            assert!(
                vs_tracer <= 0.03,
                "sd {sd}: focus {focus} vs the tracer's {traced}"
            );
            assert!(
                vs_paraxial <= 0.03,
                "sd {sd}: focus {focus} vs paraxial {paraxial}"
            );
        }
    });
}

/// A glass wedge (η 1.5) whose exit face meets the light at `angle` degrees: past the
/// critical angle (41.8°) total internal reflection lets no light through the face.
/// Returns the mean irradiance, relative to the unobstructed light, on a plane behind the
/// face over the pixels whose light had to cross it.
fn light_beyond_wedge(ctx: &Context, angle: f32, transport: LightTransport) -> f64 {
    light_beyond_graded_wedge(ctx, angle, transport, None, 1.0)
}

/// `light_beyond_wedge` with the faces graded as tanh ramps `ramp` voxels wide (10-90 %
/// of the step of η), when given, at sample distance `sd`.
fn light_beyond_graded_wedge(
    ctx: &Context,
    angle: f32,
    transport: LightTransport,
    ramp: Option<f32>,
    sd: f32,
) -> f64 {
    let n = 64u32;
    let a = angle.to_radians();
    // Light travels along world -z (the camera looks down -z) into the wedge's entry face;
    // its exit face makes `angle` with the light; the faces meet outside the box, so no
    // light reaches the edge between them.
    let vol = glass_wedge(n, angle, ramp);
    let cam = face_on(2.5, 12.0);
    let (w, h) = (64u32, 64u32);
    let planes = Planes::for_box(&cam, Vec3::splat(0.5), sd / n as f32).unwrap();
    let last = planes.count - 1;
    let mut opts = frame_options(w, h, sd);
    opts.sweep = SweepOptions {
        light_transport: transport,
        dumps: vec![(StateBuffer::LightColour, last)],
        // The fraction of the power beyond the face.
        plane_flux: true,
        ..Default::default()
    };
    opts.lights = vec![headlight(&cam, 0.0)];
    let f = sweep(ctx, &vol, &glass(1.5), &cam, &opts);
    let d = f.dumps.iter().find(|d| d.plane == last).unwrap();
    let depth = planes.depth(last);
    // Pixels whose straight light path crosses the exit face inside the box: the central
    // square, where the face lies between z = 0.3 and the last plane.
    let t = (cam.fov_y.to_radians() * 0.5).tan();
    let (mut sum, mut count) = (0.0f64, 0);
    for y in 0..h {
        for x in 0..w {
            let px = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * depth * t;
            let py = -((y as f32 + 0.5) / h as f32 * 2.0 - 1.0) * depth * t;
            // World (x, y) = view (x, y) for this camera. The face at x: z = -0.1 + x tan a
            // must lie in front of the last plane (world z = cam.distance - depth).
            let zf = -0.1 + px * a.tan();
            if px.abs() < 0.3 && py.abs() < 0.3 && zf > cam.distance - depth + 0.05 && zf < 0.4 {
                sum += d.pixels[(y * w + x) as usize][0] as f64;
                count += 1;
            }
        }
    }
    assert!(count > 50, "too few pixels behind the face ({count})");
    sum / count as f64
}

#[test]
fn total_internal_reflection_lets_no_light_through_a_wedge() {
    with_context(|ctx| {
        // 47° and 50°: 5° and 8° past the critical angle. Nearer to it the direction of a
        // one-voxel surface's normal decides, and ours is good to a degree or two: 42°
        // passes 25 %, 43° 19 %, 45° 2.7 % (measured; docs/NOTES.md).
        let results: Vec<(f32, f64)> = [47.0f32, 50.0]
            .into_iter()
            .map(|a| (a, light_beyond_wedge(ctx, a, LightTransport::Forward)))
            .collect();
        for (angle, passed) in &results {
            println!(
                "exit face at {angle}°: {:.2} % of the light beyond it",
                passed * 100.0
            );
        }
        for (angle, passed) in results {
            assert!(passed <= 0.02, "{angle}°: {:.1} % passed", passed * 100.0);
        }
        // For the record (docs/NOTES.md), nearer the critical angle.
        for angle in [42.0f32, 43.0, 45.0] {
            let passed = light_beyond_wedge(ctx, angle, LightTransport::Forward);
            println!(
                "exit face at {angle}° (not asserted): {:.2} % beyond it",
                passed * 100.0
            );
        }
        // Graded faces (issue 32, "faces found whole"): tanh ramps 2 and 3 voxels wide
        // (10-90 % of the step) reflect as totally, at sample distance 1 and 0.5. Measured
        // 2026-11-27: at most 0.43 % at 47°, 0 at 50-55°, 1.49 % at 60° with the 2-voxel
        // ramp; 42° passes 19-26 %, 45° 0.2-1.4 % (docs/NOTES.md).
        for sd in [1.0f32, 0.5] {
            for ramp in [2.0f32, 3.0] {
                for angle in [47.0f32, 55.0, 60.0] {
                    let passed = light_beyond_graded_wedge(
                        ctx,
                        angle,
                        LightTransport::Forward,
                        Some(ramp),
                        sd,
                    );
                    println!(
                        "exit face graded over {ramp} voxels at {angle}°, sample distance \
                         {sd}: {:.2} % beyond it",
                        passed * 100.0
                    );
                    assert!(
                        passed <= 0.02,
                        "graded over {ramp} voxels, {angle}°, sd {sd}: {:.1} % passed",
                        passed * 100.0
                    );
                }
            }
        }
        // Below the critical angle the face transmits (the same measurement can fail).
        let passed = light_beyond_wedge(ctx, 30.0, LightTransport::Forward);
        println!(
            "exit face at 30°: {:.2} % of the light beyond it",
            passed * 100.0
        );
        assert!(passed > 0.5, "30°: only {:.1} % passed", passed * 100.0);
    });
}

/// The validation scene of the field: a clear glass sphere (η 1.5, R = 24 voxels) above
/// an opaque floor (1.089 R below its centre, between the marginal and the paraxial focus),
/// a directional light 23° from the vertical, the camera straight down. The floor's light
/// from the sweep against the photon tracer on the same volume and plane: the shadow's
/// centre within 1 % R and its semi-axes within 2 % R, the caustic's brightest point within
/// 0.05 R, the mean light in discs of 0.05, 0.1 and 0.2 R around it within 20 %, the
/// caustic's extent within 15 % and the light inside the shadow within 10 %, at sample
/// distances 1 and 0.5.
#[test]
fn sphere_on_floor_caustic_matches_the_photon_tracer() {
    with_context(|ctx| {
        let scene = caustic_scene();
        let (vol, tf, cam, light) = (&scene.volume, &scene.tf, &scene.camera, scene.light);
        let (w, h, vox) = (scene.width, scene.height, scene.voxel);
        let depth_floor = scene.floor_depth();
        let r_px = scene.radius_px(depth_floor);
        let mut tracers: std::collections::HashMap<u32, (Vec<[f32; 4]>, f32)> =
            std::collections::HashMap::new();
        // The thesis' backward step is measured too, for the record (not asserted).
        for (sd, transport) in [
            (1.0f32, LightTransport::Forward),
            (0.5, LightTransport::Forward),
            (1.0, LightTransport::Backward),
            (0.5, LightTransport::Backward),
        ] {
            let planes = Planes::for_box(cam, Vec3::splat(0.5), sd * vox).unwrap();
            let k = ((depth_floor - planes.first_depth) / planes.spacing).floor() as u32;
            let mut opts = RenderOptions {
                width: w as u32,
                height: h as u32,
                sample_distance: sd,
                ..Default::default()
            };
            opts.lights = vec![light];
            opts.sweep = SweepOptions {
                light_transport: transport,
                dumps: vec![(StateBuffer::LightColour, k)],
                // Where the flux lands, as the tracer counts it (below).
                plane_flux: true,
                ..Default::default()
            };
            let f = sweep(ctx, vol, tf, cam, &opts);
            let swept = &f.dumps[0].pixels;
            let depth = planes.depth(k);
            // The tracer at this sample distance's plane (the sd-0.5 plane lies half a
            // voxel deeper, which moves the shadow by 0.9 % R along the light), once per
            // depth (both transports use the same planes).
            let tracer = tracers.entry(k).or_insert_with(|| {
                let img = refrakt::photons::trace_irradiance(
                    vol,
                    tf,
                    cam,
                    &opts,
                    depth,
                    &refrakt::photons::PhotonOptions {
                        photons_per_pixel: 16,
                        // Where the flux lands: the tracer lets photons turned beyond
                        // the sweep's 84° land, which the fluence weights by up to 10.
                        plane_flux: true,
                        ..Default::default()
                    },
                    None,
                )
                .unwrap();
                println!("{}", img.summary());
                (img.pixels, depth)
            });
            let (traced, tdepth) = (&tracer.0, tracer.1);
            let cmp = compare_floors(swept, traced, w, h, r_px);
            cmp.print(
                &format!(
                    "{} sd {sd} (plane {k}, depth {depth:.4}, tracer at {tdepth:.4})",
                    transport.name()
                ),
                "sweep",
            );
            if transport == LightTransport::Backward {
                continue;
            }
            cmp.assert_close(&format!("sd {sd}"));
            assert!(
                cmp.extent <= 0.15,
                "sd {sd}: caustic extent off by {:.0} %",
                cmp.extent * 100.0
            );
        }
    });
}

/// The demo's own geometry seen from straight above (the scene of the two tests below):
/// `sphere-on-floor` at 64³ with its `glass-floor` transfer functions, a light 16° off
/// the vertical, 128², and the view depth 2.5 voxels above the floor with the ball's
/// radius there in pixels.
struct DemoFromAbove {
    vox: f32,
    vol: refrakt::volume::Volume,
    tf: TransferFunctions,
    cam: Camera,
    light: Light,
    w: usize,
    h: usize,
    depth_floor: f32,
    r_px: f64,
}

impl DemoFromAbove {
    fn new() -> Self {
        let n = 64u32;
        let vox = 1.0 / n as f32;
        let (r, floor_top) = (0.24f32, -0.38f32);
        let cam = Camera {
            azimuth: 0.0,
            elevation: 90.0,
            distance: 2.2,
            fov_y: 35.0,
            ..Default::default()
        };
        let (w, h) = (128usize, 128usize);
        let depth_floor = cam.distance - (floor_top + 2.5 * vox);
        let t = (cam.fov_y.to_radians() * 0.5).tan();
        Self {
            vox,
            vol: refrakt::volume::procedural::sphere_on_floor(n).unwrap(),
            tf: TransferFunctions::load("glass-floor").unwrap(),
            cam,
            light: Light {
                source: refrakt::light::LightSource::Directional {
                    towards: Vec3::new(0.25, 1.0, -0.15).normalize(),
                },
                colour: [1.0; 3],
                softness: 0.0,
            },
            w,
            h,
            depth_floor,
            r_px: r as f64 * h as f64 / (2.0 * depth_floor as f64 * t as f64),
        }
    }

    /// The photon tracer's irradiance at view depth `depth`.
    fn traced(&self, opts: &RenderOptions, depth: f32, photons_per_pixel: u32) -> Vec<[f32; 4]> {
        let photons = refrakt::photons::PhotonOptions {
            photons_per_pixel,
            plane_flux: true,
            ..Default::default()
        };
        refrakt::photons::trace_irradiance(
            &self.vol, &self.tf, &self.cam, opts, depth, &photons, None,
        )
        .unwrap()
        .pixels
    }

    /// The planes at sample distance `sd`, and options that dump the irradiance of the
    /// last plane before the floor's depth.
    fn floor_plane(&self, sd: f32) -> (Planes, RenderOptions) {
        let planes = Planes::for_box(&self.cam, Vec3::splat(0.5), sd * self.vox).unwrap();
        let k = ((self.depth_floor - planes.first_depth) / planes.spacing).floor() as u32;
        let mut opts = RenderOptions {
            width: self.w as u32,
            height: self.h as u32,
            sample_distance: sd,
            ..Default::default()
        };
        opts.sweep = SweepOptions {
            dumps: vec![(StateBuffer::LightColour, k)],
            // Where the flux lands and its power, as the tracer counts them.
            plane_flux: true,
            ..Default::default()
        };
        opts.lights = vec![self.light];
        (planes, opts)
    }
}

/// The demo's own geometry (`sphere-on-floor`, here at 64³, with its `glass-floor`
/// transfer functions: the floor's value ramp passes the glass's η band, a film): the
/// floor lies 0.67 R below the ball, beyond its paraxial focus (1.5 R from the centre),
/// so the light through the ball has crossed the axis before it lands. Seen from straight
/// above, on the plane 2.5 voxels above the floor, the sweep's irradiance must agree with
/// the photon tracer's ring by ring around the caustic (annuli 0.15 R wide out to 1.35 R:
/// the focus, the dark shadow, the bright ring at its edge and the lit floor beyond),
/// within 25 % each, and in power within 1 %, at sample distances 1 and 0.5.
#[test]
fn the_demos_caustic_matches_the_photon_tracer_ring_by_ring() {
    with_context(|ctx| {
        let demo = DemoFromAbove::new();
        let (w, h, r_px) = (demo.w, demo.h, demo.r_px);
        for sd in [1.0f32, 0.5] {
            let (planes, opts) = demo.floor_plane(sd);
            let k = opts.sweep.dumps[0].1;
            let f = sweep(ctx, &demo.vol, &demo.tf, &demo.cam, &opts);
            let swept = &f.dumps[0].pixels;
            let traced = demo.traced(&opts, planes.depth(k), 16);
            let power = |img: &[[f32; 4]]| img.iter().map(|p| p[0] as f64).sum::<f64>();
            let (pa, pb) = (power(swept), power(&traced));
            println!("sd {sd} (plane {k}): power sweep {pa:.1}, tracer {pb:.1}");
            assert!((pa - pb).abs() / pb <= 0.01, "sd {sd}: power {pa} vs {pb}");
            let centre = measure_floor(&traced, w, h).brightest;
            let mut worst = (0.0f64, 0.0f64);
            for i in 0..9 {
                let (r0, r1) = (i as f64 * 0.15 * r_px, (i + 1) as f64 * 0.15 * r_px);
                let a = annulus_mean(swept, w, h, centre, r0, r1);
                let b = annulus_mean(&traced, w, h, centre, r0, r1);
                let e = (a - b).abs() / b;
                println!(
                    "  ring {:.2}-{:.2} R: sweep {a:.3}, tracer {b:.3} ({:+.1} %)",
                    r0 / r_px,
                    r1 / r_px,
                    (a - b) / b * 100.0
                );
                if e > worst.0 {
                    worst = (e, r0 / r_px);
                }
            }
            assert!(
                worst.0 <= 0.25,
                "sd {sd}: the ring from {:.2} R is off by {:.0} %",
                worst.1,
                worst.0 * 100.0
            );
        }
    });
}

/// Mean |a − b| / mean b of channel 0 over the pixels whose centres lie within `r` pixels
/// of `c`: the per-pixel error of an irradiance against a reference.
fn relative_l1(a: &[[f32; 4]], b: &[[f32; 4]], w: usize, c: glam::DVec2, r: f64) -> f64 {
    let (mut d, mut s) = (0.0, 0.0);
    for (k, (p, q)) in a.iter().zip(b).enumerate() {
        let at = glam::DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        if (at - c).length() < r {
            d += (p[0] as f64 - q[0] as f64).abs();
            s += q[0] as f64;
        }
    }
    d / s
}

/// The demo's caustic per pixel (the scene of the ring-by-ring test above): the rays'
/// spacing, not their paths, limits how closely the splatted irradiance follows the
/// photon tracer's (docs/NOTES.md: the tracer's four-armed star, arms thinner than a
/// pixel). Inside the shadow the per-pixel error against a tracer with 64 photons per
/// pixel falls as the spacing does: a tenth or more from 1 to 0.6 pixels (2.8 times the
/// rays; 0.5 would need more than 8 rays per screen pixel in this view), and spacing 2 is
/// half again as far off as 1. Measured: 0.43, 0.19, 0.15 (at 256 photons per pixel 0.42,
/// 0.18, 0.14 at spacing 0.57). Power stays within 1 % at every spacing. A wrong path
/// would not converge with the spacing, and a deposit that depended on the rays' number
/// (an amplitude not normalised per ray) would break the power.
#[test]
fn a_finer_light_spacing_converges_the_caustic_to_the_photon_tracer() {
    with_context(|ctx| {
        let demo = DemoFromAbove::new();
        let (w, h, r_px) = (demo.w, demo.h, demo.r_px);
        let (planes, plain) = demo.floor_plane(1.0);
        let k = plain.sweep.dumps[0].1;
        let opts = |spacing: f32| {
            let mut o = plain.clone();
            o.sweep.light_rays = 8;
            o.sweep.light_spacing = spacing;
            o
        };
        let traced = demo.traced(&opts(1.0), planes.depth(k), 64);
        let centre = measure_floor(&traced, w, h).brightest;
        let power = |img: &[[f32; 4]]| img.iter().map(|p| p[0] as f64).sum::<f64>();
        let mut errors = Vec::new();
        for spacing in [2.0f32, 1.0, 0.6] {
            let f = sweep(ctx, &demo.vol, &demo.tf, &demo.cam, &opts(spacing));
            let stats = f.sweep.as_ref().unwrap();
            let swept = &f.dumps[0].pixels;
            let e = relative_l1(swept, &traced, w, centre, r_px);
            let (pa, pb) = (power(swept), power(&traced));
            println!(
                "spacing {spacing} (launched {:.3}, {} × {} rays): per-pixel error in the \
                 shadow {e:.4}, power {pa:.1} vs {pb:.1}",
                stats.light_spacing[1], stats.light_rays[0], stats.light_rays[1]
            );
            assert!(
                stats.light_spacing[1] <= spacing,
                "spacing {spacing} launched at {}",
                stats.light_spacing[1]
            );
            assert!(
                (pa - pb).abs() / pb <= 0.01,
                "spacing {spacing}: power {pa} vs {pb}"
            );
            errors.push(e);
        }
        let [coarse, plain, fine] = [errors[0], errors[1], errors[2]];
        assert!(
            coarse >= 1.5 * plain,
            "spacing 2: {coarse} against spacing 1: {plain}"
        );
        assert!(
            fine <= 0.9 * plain,
            "spacing 0.6: {fine} against spacing 1: {plain}"
        );
    });
}

//! Issue 17 (seed 002): the hard shadow of an opaque ball on a floor, lit obliquely, from
//! the single-scattering model (`--model single`, g = 0: a per-voxel transmittance cache
//! marched towards the light, sampled by a ray marcher) and from the refractive plane
//! sweep with η ≡ 1 and softness 0 (light carried plane by plane from the camera's side):
//! two independent implementations of the same shadow, whose centre and principal axes on
//! the floor must agree within one voxel with each other and with the geometric shadow
//! (the ball projected along the light onto the floor plane), so that a bug shared by both
//! models (a light-direction convention, say) fails too.

mod common;

use common::{f32_volume, with_context};
use glam::{DVec2, Vec3};
use refrakt::render::{
    Camera, Frame, Light, Model, RenderOptions, Renderer, ScatterOptions, SweepOptions,
};
use refrakt::transfer::{Piecewise, TransferFunctions};

/// Voxels per side of the volume (the unit box): one voxel is 1/N world units.
const N: u32 = 64;
/// Image side in pixels.
const SIZE: u32 = 128;
/// The floor's top surface (world y): 7 voxels above the box's bottom.
const FLOOR_TOP: f32 = -0.5 + 7.0 / N as f32;
/// The ball: radius and centre (world), 39 voxels above the floor and off the vertical
/// axis towards the light, so that seen from above neither hides the other's shadow.
const RADIUS: f32 = 9.0 / N as f32;
/// Light: angle from the floor's normal and azimuth about it (degrees from +x towards +z).
const LIGHT_POLAR_DEG: f32 = 35.0;
const LIGHT_AZIMUTH_DEG: f32 = 40.0;
/// Opacity per reference step of the material (ball and floor): opaque-ish, so the floor
/// shows its light a fraction of a voxel deep, the same way to both models.
const ALPHA: f32 = 0.9;
/// Sample distance of both models (half a voxel).
const SAMPLE_DISTANCE: f32 = 0.5;

fn voxel() -> f32 {
    1.0 / N as f32
}

fn light_azimuth() -> Vec3 {
    let p = LIGHT_AZIMUTH_DEG.to_radians();
    Vec3::new(p.cos(), 0.0, p.sin())
}

fn ball_centre() -> Vec3 {
    let h = 39.0 * voxel();
    light_azimuth() * 0.23 + Vec3::new(0.0, FLOOR_TOP + h, 0.0)
}

/// Unit direction towards the light.
fn towards(polar_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (t, p) = (polar_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin())
}

/// Ball and floor slab of one material: value 1 inside either, 0 outside, with one-voxel
/// ramps (value 0.5 on the surfaces).
fn scene_volume() -> refrakt::volume::Volume {
    let n = N as f32;
    let c = ball_centre();
    f32_volume(N, |p| {
        let p = Vec3::from(p);
        let ball = 0.5 + (RADIUS - (p - c).length()) * n;
        let floor = 0.5 + (FLOOR_TOP - p.y) * n;
        ball.max(floor)
    })
}

/// Opacity [`ALPHA`] above value 0.5 (a step at the surfaces), white, η ≡ 1 (the default
/// η channel: the sweep's η' = 1 + k (η_tf − 1) is then 1 whatever the scale k).
fn scene_tf() -> TransferFunctions {
    TransferFunctions {
        opacity: Piecewise::new(vec![
            (0.0, [0.0]),
            (0.49, [0.0]),
            (0.5, [ALPHA]),
            (1.0, [ALPHA]),
        ]),
        eta: Piecewise::constant([1.0]),
        ..Default::default()
    }
}

/// Straight down onto the floor: screen right is world +x, screen down is world +z.
fn camera() -> Camera {
    Camera {
        azimuth: 0.0,
        elevation: 90.0,
        distance: 2.5,
        fov_y: 26.0,
        ..Default::default()
    }
}

/// An ellipse on the floor, in voxels (x, z from the box's centre).
#[derive(Clone, Copy, Debug)]
struct Ellipse {
    centre: DVec2,
    /// Semi-major, semi-minor.
    semi_axes: [f64; 2],
    /// Direction of the major axis, radians in (-π/2, π/2].
    angle: f64,
}

impl std::fmt::Display for Ellipse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "centre ({:.2}, {:.2}) vox, semi-axes {:.2} / {:.2} vox, major axis at {:.1}°",
            self.centre.x,
            self.centre.y,
            self.semi_axes[0],
            self.semi_axes[1],
            self.angle.to_degrees()
        )
    }
}

/// The geometric shadow: the ball's centre projected along `light` onto the floor plane,
/// semi-axes R / cos θ (along the light's azimuth) and R.
fn analytic(light: Vec3) -> Ellipse {
    let c = ball_centre();
    let l = light.normalize();
    let on_floor = c - l * ((c.y - FLOOR_TOP) / l.y);
    let n = N as f64;
    let r = RADIUS as f64 * n;
    Ellipse {
        centre: DVec2::new(on_floor.x as f64, on_floor.z as f64) * n,
        semi_axes: [r / l.y as f64, r],
        angle: wrap_axis((l.z as f64).atan2(l.x as f64)),
    }
}

/// An axis direction folded into (-π/2, π/2].
fn wrap_axis(a: f64) -> f64 {
    let mut a = a % std::f64::consts::PI;
    if a <= -std::f64::consts::FRAC_PI_2 {
        a += std::f64::consts::PI;
    } else if a > std::f64::consts::FRAC_PI_2 {
        a -= std::f64::consts::PI;
    }
    a
}

/// Where pixel (x, y)'s centre sees the floor plane (world x, z): looking straight down,
/// a uniform scale of the pixel grid (the camera's footprint at the floor's depth).
fn floor_point(cam: &Camera, x: u32, y: u32) -> DVec2 {
    let depth = (cam.eye().y - FLOOR_TOP) as f64;
    let t = (0.5 * cam.fov_y as f64).to_radians().tan();
    let nx = (x as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
    let ny = (y as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
    DVec2::new(depth * nx * t, depth * ny * t)
}

/// Whether the eye's ray through pixel (x, y) passes within `margin` of the ball.
fn sees_ball(cam: &Camera, x: u32, y: u32, margin: f32) -> bool {
    let eye = cam.eye();
    let f = floor_point(cam, x, y);
    let dir = (Vec3::new(f.x as f32, FLOOR_TOP, f.y as f32) - eye).normalize();
    let to_c = ball_centre() - eye;
    let along = to_c.dot(dir);
    (to_c - along * dir).length() <= RADIUS + margin
}

fn luminance(p: [f32; 4]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64
}

/// The floor's pixels: inside the box (two voxels from its sides), not looking at the
/// ball (with two voxels of margin).
fn floor_mask(cam: &Camera) -> Vec<bool> {
    let mut mask = Vec::with_capacity((SIZE * SIZE) as usize);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let p = floor_point(cam, x, y);
            let inside = p.x.abs().max(p.y.abs()) < 0.5 - 2.0 / N as f64;
            mask.push(inside && !sees_ball(cam, x, y, 2.0 * voxel()));
        }
    }
    mask
}

/// The shadow on the floor of a rendered frame: lit floor (median of the floor's pixels)
/// and umbra (mean of its darkest 1 %) measured from the image, the shadow where the floor
/// is darker than half-way between them; its centroid and the semi-axes of the uniform
/// ellipse with its second moments, in voxels on the floor plane. Panics if the shadow
/// touches the edge of the floor region (it would be cut off).
fn measure(frame: &Frame, cam: &Camera, mask: &[bool], name: &str) -> Ellipse {
    let mut floor: Vec<f64> = frame
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| luminance(*p))
        .collect();
    floor.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let lit = floor[floor.len() / 2];
    let dark = floor.len() / 100;
    let umbra = floor[..dark].iter().sum::<f64>() / dark as f64;
    let threshold = 0.5 * (lit + umbra);
    println!("{name}: lit floor {lit:.4}, umbra {umbra:.4}, threshold {threshold:.4}");
    assert!(
        lit > 0.05 && umbra < 0.1 * lit,
        "{name}: no clear shadow (lit floor {lit}, umbra {umbra})"
    );
    let n = N as f64;
    let idx = |x: u32, y: u32| (y * SIZE + x) as usize;
    let (mut count, mut sum) = (0.0f64, DVec2::ZERO);
    let mut points = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            if !mask[idx(x, y)] || luminance(frame.pixel(x, y)) >= threshold {
                continue;
            }
            // Every shadow pixel's neighbours are floor: the shadow is whole.
            for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
                let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                let inside = (0..SIZE as i32).contains(&nx) && (0..SIZE as i32).contains(&ny);
                assert!(
                    inside && mask[idx(nx as u32, ny as u32)],
                    "{name}: shadow pixel ({x}, {y}) touches the edge of the floor region"
                );
            }
            let p = floor_point(cam, x, y) * n;
            count += 1.0;
            sum += p;
            points.push(p);
        }
    }
    assert!(count > 50.0, "{name}: only {count} shadow pixels");
    let c = sum / count;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in &points {
        let d = *p - c;
        sxx += d.x * d.x;
        syy += d.y * d.y;
        sxy += d.x * d.y;
    }
    let (sxx, syy, sxy) = (sxx / count, syy / count, sxy / count);
    let mean = 0.5 * (sxx + syy);
    let spread = ((0.5 * (sxx - syy)).powi(2) + sxy * sxy).sqrt();
    // A uniform ellipse of semi-axis a has variance a²/4 along it.
    Ellipse {
        centre: c,
        semi_axes: [2.0 * (mean + spread).sqrt(), 2.0 * (mean - spread).sqrt()],
        angle: wrap_axis(0.5 * (2.0 * sxy).atan2(sxx - syy)),
    }
}

/// The differences between two ellipses: centre distance, semi-axes, and how far the
/// major axis's end moves by the difference in orientation (all in voxels).
fn differences(a: &Ellipse, b: &Ellipse) -> [f64; 4] {
    let turn = wrap_axis(a.angle - b.angle).abs();
    [
        (a.centre - b.centre).length(),
        (a.semi_axes[0] - b.semi_axes[0]).abs(),
        (a.semi_axes[1] - b.semi_axes[1]).abs(),
        turn * a.semi_axes[0].max(b.semi_axes[0]),
    ]
}

fn assert_within_a_voxel(a: &Ellipse, b: &Ellipse, what: &str) {
    let d = differences(a, b);
    println!(
        "{what}: centre {:.2}, semi-major {:.2}, semi-minor {:.2}, orientation {:.2} vox apart",
        d[0], d[1], d[2], d[3]
    );
    assert!(
        d.iter().all(|e| *e <= 1.0),
        "{what} differ by more than a voxel (centre, semi-major, semi-minor, orientation: \
         {d:.2?} vox):\n  {a}\n  {b}"
    );
}

/// The frame as an sRGB PNG, scaled so the lit floor is mid-grey-ish.
fn save_png(frame: &Frame, lit: f64, path: &std::path::Path) {
    let scale = 0.6 / lit.max(1e-6);
    let bytes: Vec<u8> = frame
        .pixels
        .iter()
        .flat_map(|p| {
            let c = |v: f32| {
                let v = (v as f64 * scale).clamp(0.0, 1.0) as f32;
                (refrakt::tone::linear_to_srgb(v) * 255.0).round() as u8
            };
            [c(p[0]), c(p[1]), c(p[2]), 255]
        })
        .collect();
    image::save_buffer(path, &bytes, SIZE, SIZE, image::ExtendedColorType::Rgba8).unwrap();
}

#[test]
fn single_scattering_and_the_sweep_cast_the_same_shadow() {
    with_context(|ctx| {
        let cam = camera();
        let light = towards(LIGHT_POLAR_DEG, LIGHT_AZIMUTH_DEG);
        let mut renderer = Renderer::new(ctx, &scene_volume(), &scene_tf()).expect("renderer");
        let lit = |softness| Light {
            source: refrakt::light::LightSource::Directional { towards: light },
            colour: [1.0; 3],
            softness,
        };
        let mut opts = RenderOptions {
            width: SIZE,
            height: SIZE,
            sample_distance: SAMPLE_DISTANCE,
            background: [0.0, 0.0, 0.0, 1.0],
            lights: vec![lit(0.0)],
            sweep: SweepOptions {
                ..Default::default()
            },
            ..Default::default()
        };
        ScatterOptions {
            g: 0.0,
            albedo: 1.0,
        }
        .set_in(&mut opts)
        .unwrap();
        let single = renderer.render(Model::Single, &cam, &opts).unwrap();
        let swept = renderer.render(Model::Refract, &cam, &opts).unwrap();

        let mask = floor_mask(&cam);
        let a = measure(&single, &cam, &mask, "single");
        let b = measure(&swept, &cam, &mask, "sweep");
        let g = analytic(light);
        println!("single:   {a}\nsweep:    {b}\nanalytic: {g}");

        if let Ok(dir) = std::env::var("SHADOW_CROSSCHECK_PNG") {
            let dir = std::path::Path::new(&dir);
            std::fs::create_dir_all(dir).unwrap();
            let median = |f: &Frame| {
                let mut v: Vec<f64> = f
                    .pixels
                    .iter()
                    .zip(&mask)
                    .filter(|(_, m)| **m)
                    .map(|(p, _)| luminance(*p))
                    .collect();
                v.sort_by(|a, b| a.partial_cmp(b).unwrap());
                v[v.len() / 2]
            };
            save_png(&single, median(&single), &dir.join("single.png"));
            save_png(&swept, median(&swept), &dir.join("refract.png"));
        }

        // The geometry is what it claims: the ellipse is elongated along the light's
        // azimuth by more than the tolerance, so a light straight above would fail.
        assert!(g.semi_axes[0] - g.semi_axes[1] > 1.5);
        assert_within_a_voxel(&a, &b, "single and sweep");
        assert_within_a_voxel(&a, &g, "single and the geometric shadow");
        assert_within_a_voxel(&b, &g, "sweep and the geometric shadow");
    });
}

//! Shadow and caustic measurements of an irradiance image on a floor (tests/caustics.rs
//! holds the sweep to the photon tracer with them, tests/light_simulator.rs the eikonal
//! light simulator).

use super::smoothed;

/// Shadow and caustic measurements of an irradiance image on the floor, in pixels.
#[derive(Debug)]
pub struct FloorLight {
    pub centre: glam::DVec2,
    pub semi_axes: [f64; 2],
    pub brightest: glam::DVec2,
    pub bright_pixels: usize,
}

/// The shadow is where the floor's light differs from the unshadowed light by more than
/// 10 % (dark rim and caustic alike): its centroid, and the semi-axes of the uniform
/// ellipse with the same second moments. The caustic: the brightest point of the 3×3
/// smoothed image, and how many pixels are brighter than the unshadowed floor.
pub fn measure_floor(img: &[[f32; 4]], w: usize, h: usize) -> FloorLight {
    let s = smoothed(img, w, h);
    let (mut n, mut c) = (0.0f64, glam::DVec2::ZERO);
    let mut pts = Vec::new();
    let mut bright = 0;
    let mut best = (0.0f64, glam::DVec2::ZERO);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let e = img[y * w + x][0] as f64;
            let p = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            if (e - 1.0).abs() > 0.1 {
                n += 1.0;
                c += p;
                pts.push(p);
            }
            if e > 1.1 {
                bright += 1;
            }
            if s[y * w + x] > best.0 {
                best = (s[y * w + x], p);
            }
        }
    }
    c /= n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let d = *p - c;
        sxx += d.x * d.x;
        syy += d.y * d.y;
        sxy += d.x * d.y;
    }
    let (sxx, syy, sxy) = (sxx / n, syy / n, sxy / n);
    let tr = 0.5 * (sxx + syy);
    let det = ((0.5 * (sxx - syy)).powi(2) + sxy * sxy).sqrt();
    FloorLight {
        centre: c,
        semi_axes: [2.0 * (tr + det).sqrt(), 2.0 * (tr - det).sqrt()],
        brightest: best.1,
        bright_pixels: bright,
    }
}

/// Mean of channel 0 over the pixels whose centres lie from r0 (inclusive) to r1
/// (exclusive) pixels from `c`: a disc when r0 is 0.
pub fn annulus_mean(img: &[[f32; 4]], w: usize, h: usize, c: glam::DVec2, r0: f64, r1: f64) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let d = (glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - c).length();
            if d >= r0 && d < r1 {
                s += img[y * w + x][0] as f64;
                n += 1;
            }
        }
    }
    s / n.max(1) as f64
}

/// The caustics' validation scene: a clear glass sphere (η 1.5, R = 24 voxels of 64, its
/// centre 0.1 above the box's) above an opaque floor 1.089 R below its centre (between
/// the marginal and the paraxial focus), a directional light 23° from the vertical, the
/// camera straight down, 128². tests/caustics.rs holds the sweep to the photon tracer on
/// it, tests/light_simulator.rs the light simulator.
pub struct CausticScene {
    pub volume: refrakt::volume::Volume,
    pub tf: refrakt::transfer::TransferFunctions,
    pub camera: refrakt::render::Camera,
    pub light: refrakt::render::Light,
    pub width: usize,
    pub height: usize,
    /// One voxel, the sphere's radius and the floor's top (world units).
    pub voxel: f32,
    pub radius: f32,
    pub floor_top: f32,
}

pub fn caustic_scene() -> CausticScene {
    use glam::Vec3;
    use refrakt::transfer::Piecewise;
    let n = 64u32;
    let voxel = 1.0 / n as f32;
    let radius = 24.0 * voxel;
    let c = Vec3::new(0.0, 0.1, 0.0);
    let floor_top = c.y - 1.089 * radius;
    let volume = super::f32_volume(n, |p| {
        let p = Vec3::from(p);
        let sphere = 0.5 * (0.5 + (radius - (p - c).length()) * n as f32).clamp(0.0, 1.0);
        let floor = (0.5 + (floor_top - p.y) * n as f32).clamp(0.0, 1.0);
        sphere.max(floor)
    });
    let tf = refrakt::transfer::TransferFunctions {
        eta: Piecewise::new(vec![(0.0, [1.0]), (0.5, [1.5]), (0.6, [1.0])]),
        opacity: Piecewise::new(vec![(0.0, [0.0]), (0.7, [0.0]), (0.75, [1.0])]),
        ..Default::default()
    };
    let camera = refrakt::render::Camera {
        azimuth: 0.0,
        elevation: 90.0,
        distance: 2.5,
        fov_y: 30.0,
        ..Default::default()
    };
    let light = refrakt::render::Light {
        source: refrakt::light::LightSource::Directional {
            towards: -Vec3::new(0.35, -1.0, 0.25).normalize(),
        },
        colour: [1.0; 3],
        softness: 0.0,
    };
    CausticScene {
        volume,
        tf,
        camera,
        light,
        width: 128,
        height: 128,
        voxel,
        radius,
        floor_top,
    }
}

impl CausticScene {
    /// The view depth of the plane two voxels above the floor's surface ramp.
    pub fn floor_depth(&self) -> f32 {
        self.camera.distance - (self.floor_top + 2.0 * self.voxel)
    }

    /// The sphere's radius in pixels on the plane at `depth`.
    pub fn radius_px(&self, depth: f32) -> f64 {
        let t = (self.camera.fov_y.to_radians() * 0.5).tan() as f64;
        self.radius as f64 * self.height as f64 / (2.0 * depth as f64 * t)
    }
}

/// Floor image `a` against the reference `b` (w × h pixels, the sphere's radius `r_px`
/// pixels), as fractions of R or relative: the shadow's centre and semi-axes, the
/// caustic's brightest point and extent (pixels above 1.1 × the light), the mean light
/// in discs of 0.05, 0.1 and 0.2 R about b's brightest point, and the mean light inside
/// b's shadow (within its minor semi-axis of its centre), a's and b's.
pub struct FloorComparison {
    pub a: FloorLight,
    pub b: FloorLight,
    pub centre: f64,
    pub semi_axes: [f64; 2],
    pub brightest: f64,
    pub extent: f64,
    pub discs: [(f64, f64); 3],
    pub in_shadow: (f64, f64),
}

pub const DISC_RADII: [f64; 3] = [0.05, 0.1, 0.2];

pub fn compare_floors(
    a_img: &[[f32; 4]],
    b_img: &[[f32; 4]],
    w: usize,
    h: usize,
    r_px: f64,
) -> FloorComparison {
    let a = measure_floor(a_img, w, h);
    let b = measure_floor(b_img, w, h);
    let discs = DISC_RADII.map(|frac| {
        (
            annulus_mean(a_img, w, h, b.brightest, 0.0, frac * r_px),
            annulus_mean(b_img, w, h, b.brightest, 0.0, frac * r_px),
        )
    });
    let inside = |img: &[[f32; 4]]| {
        let (mut s, mut k) = (0.0, 0.0);
        for y in 0..h {
            for x in 0..w {
                let p = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - b.centre;
                if p.length() <= b.semi_axes[1] {
                    s += img[y * w + x][0] as f64;
                    k += 1.0;
                }
            }
        }
        s / k
    };
    FloorComparison {
        centre: (a.centre - b.centre).length() / r_px,
        semi_axes: [
            (a.semi_axes[0] - b.semi_axes[0]).abs() / r_px,
            (a.semi_axes[1] - b.semi_axes[1]).abs() / r_px,
        ],
        brightest: (a.brightest - b.brightest).length() / r_px,
        extent: (a.bright_pixels as f64 - b.bright_pixels as f64).abs() / b.bright_pixels as f64,
        discs,
        in_shadow: (inside(a_img), inside(b_img)),
        a,
        b,
    }
}

impl FloorComparison {
    /// Print the measurements, `what` naming image a, under `title`.
    pub fn print(&self, title: &str, what: &str) {
        println!(
            "{title}: shadow centre {:.2} % R off, semi-axes {:.2} / {:.2} % R off (tracer \
             {:.1}, {:.1} px), brightest point {:.3} R off, caustic extent {} vs {} px \
             ({:.1} %)",
            self.centre * 100.0,
            self.semi_axes[0] * 100.0,
            self.semi_axes[1] * 100.0,
            self.b.semi_axes[0],
            self.b.semi_axes[1],
            self.brightest,
            self.a.bright_pixels,
            self.b.bright_pixels,
            self.extent * 100.0
        );
        for (frac, (ma, mb)) in DISC_RADII.iter().zip(self.discs) {
            println!("  disc {frac} R around the caustic: {what} {ma:.2}, tracer {mb:.2}");
        }
        println!(
            "  mean light inside the shadow: {what} {:.3}, tracer {:.3}",
            self.in_shadow.0, self.in_shadow.1
        );
    }

    /// The bounds both tests hold (`what` names the case in the messages): the shadow's
    /// centre within 1 % R, its semi-axes within 2 % R, the brightest point within
    /// 0.05 R, the discs' means within 20 %, the light in the shadow within 10 %.
    pub fn assert_close(&self, what: &str) {
        assert!(
            self.centre <= 0.01,
            "{what}: shadow centre {:.2} % R off",
            self.centre * 100.0
        );
        assert!(
            self.semi_axes.iter().all(|e| *e <= 0.02),
            "{what}: semi-axes {:?}",
            self.semi_axes
        );
        assert!(
            self.brightest <= 0.05,
            "{what}: brightest point {:.3} R off",
            self.brightest
        );
        for (frac, (ma, mb)) in DISC_RADII.iter().zip(self.discs) {
            assert!(
                (ma - mb).abs() / mb <= 0.2,
                "{what}: disc {frac} R off by {:.0} %",
                (ma - mb).abs() / mb * 100.0
            );
        }
        let (ea, eb) = self.in_shadow;
        assert!(
            (ea - eb).abs() / eb <= 0.1,
            "{what}: light in the shadow {ea} vs {eb}"
        );
    }
}

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

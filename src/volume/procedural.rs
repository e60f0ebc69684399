//! Deterministic procedural volumes for tests and the demo. Same arguments, same bytes,
//! on every machine (integer hashing, no platform RNG).

use anyhow::{ensure, Result};

use super::{Volume, Voxels};

fn check_size(n: u32) -> Result<()> {
    ensure!(
        (2..=1024).contains(&n),
        "volume size {n} must be between 2 and 1024 voxels per axis"
    );
    Ok(())
}

/// Fill a cube of `n`³ voxels from a function of the voxel centre in [-0.5, 0.5]³ returning
/// a value in [0,1], quantised to u8.
fn from_fn(n: u32, f: impl Fn([f32; 3]) -> f32) -> Result<Volume> {
    check_size(n)?;
    let mut v = Vec::with_capacity((n as usize).pow(3));
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z].map(|i| (i as f32 + 0.5) / n as f32 - 0.5);
                v.push((f(p).clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
    }
    Volume::new([n, n, n], [1.0; 3], Voxels::U8(v))
}

fn length(p: [f32; 3]) -> f32 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// A ramp of one voxel across a boundary: 1 inside, 0 outside, 0.5 on it, so the
/// isosurface at 0.5 sits exactly at the boundary after trilinear reconstruction.
fn inside(signed_depth: f32, voxel: f32) -> f32 {
    (0.5 + signed_depth / voxel).clamp(0.0, 1.0)
}

/// A solid sphere of `radius` (fraction of the cube side) with value `value` inside.
pub fn sphere(n: u32, radius: f32, value: f32) -> Result<Volume> {
    let voxel = 1.0 / n as f32;
    from_fn(n, |p| value * inside(radius - length(p), voxel))
}

/// A slab filling the whole volume: `dims` voxels all of value `value` (as u8). Seen along
/// z its thickness is `dims[2]` voxels; the test of Beer–Lambert attenuation uses it.
pub fn slab(dims: [u32; 3], value: f32) -> Result<Volume> {
    for d in dims {
        check_size(d)?;
    }
    let n = dims.iter().map(|&d| d as usize).product();
    let q = (value.clamp(0.0, 1.0) * 255.0).round() as u8;
    Volume::new(dims, [1.0; 3], Voxels::U8(vec![q; n]))
}

/// An axis-aligned box of half-size `half` (fractions of the cube side) inside an empty
/// cube of `n`³ voxels.
pub fn boxed(n: u32, half: [f32; 3], value: f32) -> Result<Volume> {
    let voxel = 1.0 / n as f32;
    from_fn(n, |p| {
        let d = (0..3)
            .map(|i| half[i] - p[i].abs())
            .fold(f32::INFINITY, f32::min);
        value * inside(d, voxel)
    })
}

fn hash(x: i32, y: i32, z: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ (z as u32).wrapping_mul(0xcb1a_b31f)
        ^ seed.wrapping_mul(0x9e37_79b9);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0xffff) as f32 / 65535.0
}

/// Trilinearly interpolated value noise in [0,1].
fn value_noise(p: [f32; 3], seed: u32) -> f32 {
    let f = p.map(|c| c.floor());
    let t = [p[0] - f[0], p[1] - f[1], p[2] - f[2]].map(|t| t * t * (3.0 - 2.0 * t));
    let i = f.map(|c| c as i32);
    let mut acc = 0.0;
    for corner in 0..8 {
        let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        let w = (if dx == 1 { t[0] } else { 1.0 - t[0] })
            * (if dy == 1 { t[1] } else { 1.0 - t[1] })
            * (if dz == 1 { t[2] } else { 1.0 - t[2] });
        acc += w * hash(i[0] + dx, i[1] + dy, i[2] + dz, seed);
    }
    acc
}

pub(super) fn fbm(p: [f32; 3], seed: u32) -> f32 {
    let mut sum = 0.0;
    let mut amp = 0.5;
    let mut freq = 1.0;
    for o in 0..4 {
        sum += amp * value_noise(p.map(|c| c * freq), seed + o);
        amp *= 0.5;
        freq *= 2.0;
    }
    sum / 0.9375
}

/// A noisy spherical shell with a dense core, after the thesis' supernova data set
/// (Fig. 6.1): values rise towards a turbulent shell at radius ~0.3 and a small core.
pub fn shell(n: u32, seed: u32) -> Result<Volume> {
    from_fn(n, |p| shell_value(p, seed))
}

/// The shell (values scaled into [0, 0.8]) above a ground plane of value 1, as the thesis
/// adds one to Fig. 6.1 to show the shadow refracted by the shell.
pub fn shell_on_floor(n: u32, seed: u32) -> Result<Volume> {
    let voxel = 1.0 / n as f32;
    from_fn(n, |p| {
        let floor = inside(-0.42 - p[1], voxel);
        (0.8 * shell_value([p[0], p[1] + 0.04, p[2]], seed)).max(floor)
    })
}

pub(super) fn shell_value(p: [f32; 3], seed: u32) -> f32 {
    {
        let r = length(p);
        let turb = fbm(p.map(|c| c * 9.0 + 11.0), seed);
        let radius = 0.30 + 0.08 * (turb - 0.5);
        let shell = (-((r - radius) / 0.045).powi(2)).exp();
        let core = (-(r / 0.07).powi(2)).exp();
        let filaments = fbm(p.map(|c| c * 17.0 - 5.0), seed + 17);
        (shell * (0.55 + 0.45 * filaments) + 0.9 * core).min(1.0)
    }
}

/// A glass sphere (value 0.5) resting above an opaque floor (value 1) along the bottom of
/// the volume: the scene for refraction, caustics and shadows on a surface (thesis Fig. 6.9).
pub fn sphere_on_floor(n: u32) -> Result<Volume> {
    let voxel = 1.0 / n as f32;
    from_fn(n, |p| {
        let c = [0.0, 0.02, 0.0];
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let sphere = 0.5 * inside(0.24 - length(d), voxel);
        let floor = inside(-0.38 - p[1], voxel);
        sphere.max(floor)
    })
}

/// A wine glass with liquid, after the thesis' glass data set (Fig. 6.3): glass of value 0.4
/// (a bowl open at the top, a stem, a foot) holding liquid of value 0.8, for the
/// `wine-glass` transfer functions.
pub fn wine_glass(n: u32) -> Result<Volume> {
    let voxel = 1.0 / n as f32;
    from_fn(n, |p| {
        let c = [0.0, 0.1, 0.0];
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let r = length(d);
        let (r_in, r_out) = (0.24, 0.265);
        let rim = c[1] + 0.13;
        let below_rim = rim - p[1];
        let bowl = inside((r_out - r).min(r - r_in).min(below_rim), voxel);
        let radial = (p[0] * p[0] + p[2] * p[2]).sqrt();
        let stem_top = c[1] - r_out + 0.01;
        let stem = inside(
            (0.025 - radial).min(stem_top - p[1]).min(p[1] + 0.33),
            voxel,
        );
        let foot = inside((0.17 - radial).min(0.015 - (p[1] + 0.34).abs()), voxel);
        let glass = bowl.max(stem).max(foot);
        let liquid = inside((r_in - r).min(c[1] + 0.02 - p[1]), voxel);
        (0.4 * glass).max(0.8 * liquid)
    })
}

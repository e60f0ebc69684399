//! The random walks that estimate the table's entries (the module docs of `table` say
//! what they estimate), and the Henyey–Greenstein phase function they sample.

use super::*;

// ---------------------------------------------------------------------------------------
// The random walks.

/// SplitMix64: a 64-bit generator good enough for Monte-Carlo, seeded per path.
struct Rng(u64);

fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// The sequence of path `index` of stream `stream` (0: centre, 1: pole).
    fn new(seed: u64, stream: u64, index: u64) -> Self {
        Self(mix64(
            mix64(seed ^ 0x5EED_0A3B_1E17_7AB1)
                ^ mix64(index.wrapping_mul(2).wrapping_add(stream) ^ 0xA5A5_1234_9876_C3C3),
        ))
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.0)
    }

    /// Uniform in the open interval (0, 1).
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }
}

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Henyey–Greenstein normalised to mean 1 over the sphere (the pdf is this over 4π).
pub fn phase_hg(cos: f64, g: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (d * d.sqrt())
}

/// The cosine of a Henyey–Greenstein sample for a uniform `xi` (inverse CDF; Pharr &
/// Humphreys), monotonic in `xi` for every g (common random numbers stay smooth in g).
pub fn sample_hg_cos(g: f64, xi: f64) -> f64 {
    if g.abs() < 1e-4 {
        return 1.0 - 2.0 * xi;
    }
    let q = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
    ((1.0 + g * g - q * q) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// The unit vector at cosine `c` and azimuth `phi` about the unit vector `n`.
fn around(n: V3, c: f64, phi: f64) -> V3 {
    // Duff et al., "Building an orthonormal basis, revisited".
    let sign = 1.0f64.copysign(n[2]);
    let a = -1.0 / (sign + n[2]);
    let b = n[0] * n[1] * a;
    let b1 = [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
    let b2 = [b, sign + n[1] * n[1] * a, -n[1]];
    let st = (1.0 - c * c).max(0.0).sqrt();
    let (sp, cp) = phi.sin_cos();
    let (u, v) = (st * cp, st * sp);
    [
        b1[0] * u + b2[0] * v + n[0] * c,
        b1[1] * u + b2[1] * v + n[1] * c,
        b1[2] * u + b2[2] * v + n[2] * c,
    ]
}

/// An interaction vertex: position, the backward direction the walk arrived along, and
/// the throughput (albedo and roulette included).
#[derive(Clone, Copy)]
struct Vertex {
    p: V3,
    t: V3,
    w: f64,
}

#[derive(Default)]
pub(super) struct Walk {
    vertices: Vec<Vertex>,
}

impl Walk {
    /// The interaction vertices of one backward walk from `p` along `t`. Exactly four
    /// random numbers per flight, whether used or not, so that every entry sees the same
    /// sequence at the same vertex.
    fn run(&mut self, rng: &mut Rng, mut p: V3, mut t: V3, s: f64, albedo: f64, g: f64) {
        self.vertices.clear();
        let mut w = 1.0;
        loop {
            let (xd, xr, xc, xp) = (rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
            // s = 0: an infinite flight (xd < 1, so −ln xd > 0): the walk leaves.
            let dist = -xd.ln() / s;
            let b = dot(p, t);
            let c = dot(p, p) - 1.0;
            let exit = -b + (b * b - c).max(0.0).sqrt();
            if dist.is_nan() || dist >= exit {
                break;
            }
            p = [p[0] + t[0] * dist, p[1] + t[1] * dist, p[2] + t[2] * dist];
            w *= albedo;
            if w <= 0.0 {
                break;
            }
            self.vertices.push(Vertex { p, t, w });
            if w < RR_THRESHOLD {
                let survive = w / RR_THRESHOLD;
                if xr >= survive {
                    break;
                }
                w = RR_THRESHOLD;
            }
            t = around(t, sample_hg_cos(g, xc), std::f64::consts::TAU * xp);
        }
    }
}

/// Means and standard errors of `n` per-path values from their sums and sums of squares.
fn mean_err(sum: f64, sq: f64, n: u32) -> (f64, f64) {
    let nf = n as f64;
    let mean = sum / nf;
    if n < 2 {
        return (mean, 0.0);
    }
    let var = ((sq / nf - mean * mean) * nf / (nf - 1.0)).max(0.0);
    (mean, (var / nf).sqrt())
}

/// The scattered column (every θ) at (s, g): walks from the centre for ω_o = +z, each
/// rotated to every θ (ω_o(θ) = (sin θ, 0, cos θ)).
pub(super) fn scattered_column(
    params: &TableParams,
    s: f64,
    g: f64,
    walk: &mut Walk,
) -> (Vec<f64>, Vec<f64>) {
    let nt = params.theta_bins as usize;
    let rot: Vec<(f64, f64)> = (0..params.theta_bins)
        .map(|i| params.theta(i).sin_cos())
        .collect();
    let albedo = params.albedo as f64;
    let mut sum = vec![0.0f64; nt];
    let mut sq = vec![0.0f64; nt];
    let mut path = vec![0.0f64; nt];
    for j in 0..params.paths {
        let mut rng = Rng::new(params.seed, 0, j as u64);
        // ω' (the light's direction at the centre) ~ HG about ω_o = +z; walk along −ω'.
        let c = sample_hg_cos(g, rng.uniform());
        let w = around([0.0, 0.0, 1.0], c, std::f64::consts::TAU * rng.uniform());
        walk.run(&mut rng, [0.0; 3], [-w[0], -w[1], -w[2]], s, albedo, g);
        if walk.vertices.is_empty() {
            continue;
        }
        path.iter_mut().for_each(|v| *v = 0.0);
        for v in &walk.vertices {
            let r2 = dot(v.p, v.p);
            for (i, &(st, ct)) in rot.iter().enumerate() {
                // The world frame: the rotation about y taking +z to ω_o(θ).
                let z = -v.p[0] * st + v.p[2] * ct;
                let d = z + (1.0 - r2 + z * z).max(0.0).sqrt();
                // The light leaves v toward the previous vertex: along −t.
                let cos = v.t[0] * st - v.t[2] * ct;
                path[i] += v.w * phase_hg(cos, g) * (-s * d).exp();
            }
        }
        for i in 0..nt {
            sum[i] += path[i];
            sq[i] += path[i] * path[i];
        }
    }
    (0..nt)
        .map(|i| mean_err(sum[i], sq[i], params.paths))
        .unzip()
}

/// Transmission at (s, g): e^{−2s} plus the walks from the pole.
pub(super) fn transmission_entry(
    params: &TableParams,
    s: f64,
    g: f64,
    walk: &mut Walk,
) -> (f64, f64) {
    use std::f64::consts::{PI, TAU};
    let albedo = params.albedo as f64;
    let a_hg = 0.5 * g.max(0.0);
    let (mut sum, mut sq) = (0.0f64, 0.0f64);
    for j in 0..params.paths {
        let mut rng = Rng::new(params.seed, 1, j as u64);
        // The first direction: cosine-weighted about the inward normal −z, or (with
        // probability a_hg) HG about −z, where forward-peaked light comes from.
        let (x0, x1, x2) = (rng.uniform(), rng.uniform(), rng.uniform());
        let t = if x0 < a_hg {
            around([0.0, 0.0, -1.0], sample_hg_cos(g, x1), TAU * x2)
        } else {
            let r = x1.sqrt();
            let (sp, cp) = (TAU * x2).sin_cos();
            [r * cp, r * sp, -(1.0 - x1).sqrt()]
        };
        let cos = -t[2];
        if cos <= 0.0 {
            continue; // outward: nothing arrives from there (a zero estimate)
        }
        walk.run(&mut rng, [0.0, 0.0, 1.0], t, s, albedo, g);
        let mut v = 0.0;
        for x in &walk.vertices {
            let d = x.p[2] + (1.0 - x.p[0] * x.p[0] - x.p[1] * x.p[1]).max(0.0).sqrt();
            v += x.w * phase_hg(-x.t[2], g) * (-s * d).exp();
        }
        // E = ∫ L cos dω ≈ L̂·cos/q, L̂ = Σ/(4π), q the mixture's pdf (q = cos/π: Σ/4).
        let q = (1.0 - a_hg) * cos / PI + a_hg * phase_hg(cos, g) / (4.0 * PI);
        v *= cos / q / (4.0 * PI);
        sum += v;
        sq += v * v;
    }
    let (mean, err) = mean_err(sum, sq, params.paths);
    ((-2.0 * s).exp() + mean, err)
}

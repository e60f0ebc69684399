//! The preintegrated light-transport table of Ament et al. (sections 3.2 and 4.1), in a
//! physically self-consistent variant: Monte-Carlo random walks in a homogeneous sphere,
//! built on the CPU, cached on disk.
//!
//! # The quantities (lengths in units of the sphere radius r = 1)
//!
//! A homogeneous sphere of radius 1 in vacuum with extinction `s` (per unit length; the
//! paper's r·σ̃_t), albedo Λ and the Henyey–Greenstein phase function normalised to mean 1
//! over the sphere of directions, `P_HG(cos α, g) = (1 − g²)/(1 + g² − 2g cos α)^{3/2}`
//! (so `p = P_HG/(4π)` is the pdf). It is lit by a collimated beam of unit irradiance
//! travelling along +z; the beam reaches a point y inside attenuated by `exp(−s·d(y))`,
//! `d(y) = y.z + sqrt(1 − y.x² − y.y²)`.
//!
//! * **scattered(θ, s, g)** = 4π × the in-scattered radiance at the centre toward ω_o (polar
//!   angle θ from +z), counting only light scattered at least once before it reaches the
//!   centre. The single scattering of the beam at the centre itself, `e^{−s}·P_HG(cos θ, g)`,
//!   is added analytically by the renderer and is not in the table. Normalisation: the
//!   in-scattered radiance is `∫ p(ω'·ω_o) L(0, ω') dω'`; sampling ω' from p makes
//!   `L(0, ω')` its estimate, and L is estimated by a backward random walk with next-event
//!   estimation toward the beam: at each interaction vertex y (free flights of pdf
//!   `s·e^{−s t}`, which cancels σ_t, so the walk's throughput is multiplied by Λ per vertex)
//!   the beam contributes `throughput · p(cos) · e^{−s d(y)}` with `p = P_HG/(4π)`. The outer
//!   4π cancels that 1/(4π): each path's estimate is `Σ throughput · P_HG(cos) · e^{−s d(y)}`,
//!   cos between +z and the direction the light leaves y in (toward the previous vertex).
//!   For g = 0 this is the scattered fluence at the centre, and `e^{−s} + scattered` is the
//!   total fluence per unit incident irradiance.
//! * **transmission(s, g)** = the irradiance (normal +z) at the far pole (0, 0, 1) per unit
//!   incident irradiance: `e^{−2s}` (the direct beam, included) plus the scattered part,
//!   estimated from the pole by backward walks whose first direction is cosine-weighted
//!   over the inward hemisphere (irradiance = π·E[L]) and whose NEE terms carry their
//!   1/(4π): scattered part = `E[Σ throughput · P_HG · e^{−s d}]/4`. (For g > 0 the first
//!   direction comes from a mixture: with probability g/2 from HG about −z, where
//!   forward-peaked light arrives from, each estimate weighted by cos/q, q the mixture's
//!   pdf: one-sample MIS, unbiased; without it a g = 0.99 entry rested on the few walks
//!   that happened to start within ~0.01 rad of the axis.) The renderer multiplies
//!   a light front by it per tube-marching step of 2r (the paper's eq. 16 with this
//!   consistent quantity in place of L̃_o(0, …)). It is 1 at s = 0, `e^{−2s}` at Λ = 0 and
//!   at most 1.
//!
//! Walks stop when a free flight leaves the sphere (vacuum: the beam is a delta and is
//! handled by the next-event estimation) and, once the throughput falls below
//! [`RR_THRESHOLD`], by Russian roulette (survivors are reweighted: unbiased).
//!
//! # Axes (node-centred: the GPU's linear filtering hits the nodes at texel centres)
//!
//! `θ_i = π·i/(Nθ−1)`, `s_k = (1 + S_MAX)^(k/(Ns−1)) − 1`, `g_m = −0.99 + 1.98·m/(Ng−1)`.
//! The s axis is linear near 0 (spacing ln(1 + S_MAX)/(Ns−1) ≈ 0.09 there) and geometric
//! beyond s ≈ 1: both tables grow in proportion to s at first, and the renderer multiplies
//! hundreds of transmissions along a tube, so an axis in √s (quadratic nodes), which
//! interpolates a linear start like √s, dimmed light crossing thin media by tens of
//! percent over a box (measured: 25 % with 12 nodes, tests/ambient.rs). [`TableParams::theta_coord`], [`TableParams::s_coord`]
//! and [`TableParams::g_coord`] give the continuous index of a value (mirror them in GLSL:
//! texel coordinate = (index + 0.5)/N). Layout: `scattered[(m·Ns + k)·Nθ + i]` (θ fastest,
//! then s, then g: a 3D texture of extent [Nθ, Ns, Ng]); `transmission[m·Ns + k]` (a 2D
//! texture [Ns, Ng]); the standard errors in the same layouts.
//!
//! Beyond S_MAX the lookups return the last column (s = S_MAX). For the default parameters
//! (measured on this machine) the last column's largest scattered value is 1.7e-5 of the
//! table's maximum (≈ 2100, the g = 0.99 forward peak at small s; the s = 0 row itself is
//! identically 0), i.e. about 0.036, and only at g = 0.99, where the forward-peaked walk
//! still carries light through; for |g| ≤ 0.9 it is below 1.5e-9 of the maximum (below
//! 1e-22 for |g| ≤ 0.5). The last transmission column is below 4e-11 everywhere.
//!
//! # Noise, speed, reproducibility
//!
//! Every entry uses the same random sequence (common random numbers, seeded by the seed
//! and the path index only), so the table's error is a smooth function of (θ, s, g) rather
//! than per-entry speckle, and the table is bit-identical for any thread count. The walks
//! of one (s, g) are shared by every θ (the sphere is symmetric about its centre: the walk
//! for ω_o(θ) is the walk for +z rotated), so a column costs one set of walks.
//!
//! Default parameters, measured on this 2-core machine (release build, 2 threads): see
//! [`TableParams::default`].
//!
//! Limits: near g = ±0.99 the estimates are heavy-tailed (the next-event term P_HG reaches
//! 2·10⁴ within ~0.01 rad), so their standard errors are large and themselves uncertain.
//! Transmission at g = 0.99, Λ = 0.9 (defaults): 0.76 ± 0.07 at s = 1, 0.19 ± 0.08 at
//! s = 8.4, and 3e-11 ± 2e-11 at s = 64, where absorption alone would allow up to
//! e^{−2s(1−Λ)} ≈ 3e-6: the walks that follow the forward-peaked beam through a dense
//! sphere are too rare for 8192 paths, so treat those entries as lower estimates.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{anyhow, bail, ensure, Context, Result};

mod file;
mod walks;
pub use file::{cache_dir, check_target, load_or_build, Existing, FORMAT_VERSION, MAGIC};
pub use walks::{phase_hg, sample_hg_cos};
use walks::{scattered_column, transmission_entry, Walk};

/// The anisotropy axis' ends.
pub const G_MIN: f32 = -0.99;
pub const G_MAX: f32 = 0.99;
/// Russian roulette starts when a walk's throughput falls below this.
pub const RR_THRESHOLD: f64 = 0.05;

/// What a table is built from; also the key of its cache file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableParams {
    /// Single-scattering albedo Λ in [0, 1].
    pub albedo: f32,
    /// Nθ: nodes of the scattering angle over [0, π].
    pub theta_bins: u32,
    /// Ns: nodes of the extinction over [0, s_max], linear near 0, geometric beyond 1.
    pub s_bins: u32,
    /// Ng: nodes of the anisotropy over [−0.99, 0.99].
    pub g_bins: u32,
    /// The largest extinction (per sphere radius).
    pub s_max: f32,
    /// Random walks per entry.
    pub paths: u32,
    /// Seed of the random sequence (the same for every entry).
    pub seed: u64,
}

impl Default for TableParams {
    /// Albedo 0.9, 33 × 48 × 23 nodes, s_max 64, 8192 walks per entry.
    ///
    /// Measured on this 2-core machine (release, 2 threads, other jobs running): 82 s.
    /// Relative standard errors, per g column over the entries above 1e-2 of that
    /// column's maximum: median 1.7–2.5 % for |g| ≤ 0.55, 3–6 % for |g| ≥ 0.63, largest
    /// 7 % (g = 0) to 19 % (the largest are the small values at large s). Over the entries
    /// above 1e-3 of the whole table's maximum (the CLI's figure; that maximum is the
    /// g = 0.99 forward peak, so it selects mostly |g| ≥ 0.8): 45 %, at g = ±0.99, where
    /// the phase function's peak (P_HG up to 2·10⁴) makes the next-event estimate spiky.
    /// Transmission, over entries above 1e-2: ≤ 6 % for |g| ≤ 0.72, 11 % at g = 0.9 and
    /// 64–68 % at g = ±0.99 (heavy-tailed there, see the module documentation).
    fn default() -> Self {
        Self {
            albedo: 0.9,
            theta_bins: 33,
            s_bins: 48,
            g_bins: 23,
            s_max: 64.0,
            paths: 8192,
            seed: 1,
        }
    }
}

impl TableParams {
    /// Refuse parameters the table cannot be built from, saying which and why.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.albedo.is_finite() && (0.0..=1.0).contains(&self.albedo),
            "albedo {} must lie in [0, 1]",
            self.albedo
        );
        for (name, n) in [
            ("theta bins", self.theta_bins),
            ("extinction bins", self.s_bins),
            ("g bins", self.g_bins),
        ] {
            ensure!(n >= 2, "{name} {n} must be at least 2");
            ensure!(n <= 4096, "{name} {n} must be at most 4096");
        }
        // Extinction per radius beyond a few thousand leaves nothing scattered to tabulate
        // (--s-max 1e30 built an all-zero table without a word).
        ensure!(
            self.s_max.is_finite() && self.s_max > 0.0 && self.s_max <= 4096.0,
            "s_max {} must be a number in (0, 4096]",
            self.s_max
        );
        ensure!(self.paths >= 1, "paths {} must be at least 1", self.paths);
        Ok(())
    }

    /// Nθ·Ns·Ng.
    pub fn entries(&self) -> usize {
        self.theta_bins as usize * self.s_bins as usize * self.g_bins as usize
    }

    /// θ of node i.
    pub fn theta(&self, i: u32) -> f64 {
        std::f64::consts::PI * i as f64 / (self.theta_bins - 1) as f64
    }

    /// s of node k.
    pub fn s(&self, k: u32) -> f64 {
        let t = k as f64 / (self.s_bins - 1) as f64;
        (1.0 + self.s_max as f64).powf(t) - 1.0
    }

    /// g of node m.
    pub fn g(&self, m: u32) -> f64 {
        G_MIN as f64 + (G_MAX - G_MIN) as f64 * m as f64 / (self.g_bins - 1) as f64
    }

    /// Continuous node index of θ (radians), clamped to [0, Nθ−1].
    pub fn theta_coord(&self, theta: f32) -> f32 {
        let n = (self.theta_bins - 1) as f32;
        (theta / std::f32::consts::PI * n).clamp(0.0, n)
    }

    /// Continuous node index of s, clamped to [0, Ns−1] (s beyond s_max: the last node).
    pub fn s_coord(&self, s: f32) -> f32 {
        let n = (self.s_bins - 1) as f32;
        ((1.0 + s.max(0.0)).ln() / (1.0 + self.s_max).ln() * n).clamp(0.0, n)
    }

    /// Continuous node index of g, clamped to [0, Ng−1].
    pub fn g_coord(&self, g: f32) -> f32 {
        let n = (self.g_bins - 1) as f32;
        ((g - G_MIN) / (G_MAX - G_MIN) * n).clamp(0.0, n)
    }

    /// The parameters where `self` differs from `wanted`, e.g. "seed 1, wanted 3".
    pub fn differences(&self, wanted: &TableParams) -> String {
        let (a, b) = (self, wanted);
        let mut d = Vec::new();
        let mut add = |name: &str, x: String, y: String| {
            if x != y {
                d.push(format!("{name} {x}, wanted {y}"));
            }
        };
        add("albedo", a.albedo.to_string(), b.albedo.to_string());
        add(
            "theta bins",
            a.theta_bins.to_string(),
            b.theta_bins.to_string(),
        );
        add(
            "extinction bins",
            a.s_bins.to_string(),
            b.s_bins.to_string(),
        );
        add("g bins", a.g_bins.to_string(), b.g_bins.to_string());
        add("s_max", a.s_max.to_string(), b.s_max.to_string());
        add("paths", a.paths.to_string(), b.paths.to_string());
        add("seed", a.seed.to_string(), b.seed.to_string());
        d.join("; ")
    }

    /// The cache file's name: every parameter and the format version.
    pub fn file_name(&self) -> String {
        format!(
            "ambient-a{:.3}-t{}-s{}-g{}-m{}-p{}-seed{}-v{}.bin",
            self.albedo,
            self.theta_bins,
            self.s_bins,
            self.g_bins,
            self.s_max,
            self.paths,
            self.seed,
            FORMAT_VERSION
        )
    }
}

/// The table: values and Monte-Carlo standard errors (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct AmbientTable {
    pub params: TableParams,
    /// `[(m·Ns + k)·Nθ + i]`.
    pub scattered: Vec<f32>,
    pub scattered_err: Vec<f32>,
    /// `[m·Ns + k]`, the direct beam e^{−2s} included.
    pub transmission: Vec<f32>,
    pub transmission_err: Vec<f32>,
    /// Wall seconds the build took.
    pub build_seconds: f64,
}

/// A finished work unit: its index, the means and the standard errors.
type Done = (usize, Vec<f64>, Vec<f64>);

/// Where [`load_or_build`]'s table came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// Read from this file.
    Cached(PathBuf),
    /// Built in `seconds`; `written` is the file it was saved to (`None`: saving failed,
    /// a warning was logged).
    Built {
        seconds: f64,
        written: Option<PathBuf>,
    },
}

/// The largest standard errors of a table (see [`AmbientTable::errors`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorSummary {
    /// The largest scattered value.
    pub scattered_max: f32,
    /// The largest relative standard error over the scattered entries above 1e-3 of the
    /// largest value.
    pub scattered_rel: f32,
    /// The largest absolute standard error of the scattered entries.
    pub scattered_abs: f32,
    /// The same for transmission (entries above 1e-3 of its largest value).
    pub transmission_rel: f32,
    pub transmission_abs: f32,
}

impl AmbientTable {
    /// Build the table with `threads` workers (0: all cores), calling `progress(done,
    /// total)` as columns finish. Bit-identical for any thread count.
    pub fn build(
        params: &TableParams,
        threads: usize,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Self> {
        params.validate()?;
        let start = Instant::now();
        let (nt, ns, ng) = (
            params.theta_bins as usize,
            params.s_bins as usize,
            params.g_bins as usize,
        );
        let columns = ns * ng;
        let units = 2 * columns;
        let threads = crate::workers::count(threads)?.min(units);
        let next = AtomicUsize::new(0);
        let done = AtomicU64::new(0);
        // Unit u < columns: the scattered column (k, m), largest s first (the longest walks
        // start early); then the transmission entries.
        let unit = |u: usize| -> (bool, usize, usize) {
            let c = u % columns;
            (u < columns, ns - 1 - c / ng, c % ng)
        };
        let work = || {
            let mut out: Vec<Done> = Vec::new();
            let mut walk = Walk::default();
            loop {
                let u = next.fetch_add(1, Ordering::Relaxed);
                if u >= units {
                    break;
                }
                let (scattered, k, m) = unit(u);
                let (s, g) = (params.s(k as u32), params.g(m as u32));
                let (mean, err) = if scattered {
                    scattered_column(params, s, g, &mut walk)
                } else {
                    let (v, e) = transmission_entry(params, s, g, &mut walk);
                    (vec![v], vec![e])
                };
                out.push((u, mean, err));
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(d, units as u64);
            }
            out
        };
        let parts: Vec<Vec<Done>> = crate::workers::run(threads, "ambient table", work)?;
        let mut table = Self {
            params: *params,
            scattered: vec![0.0; nt * ns * ng],
            scattered_err: vec![0.0; nt * ns * ng],
            transmission: vec![0.0; ns * ng],
            transmission_err: vec![0.0; ns * ng],
            build_seconds: 0.0,
        };
        for (u, mean, err) in parts.into_iter().flatten() {
            let (scattered, k, m) = unit(u);
            let col = m * ns + k;
            if scattered {
                for i in 0..nt {
                    table.scattered[col * nt + i] = mean[i] as f32;
                    table.scattered_err[col * nt + i] = err[i] as f32;
                }
            } else {
                table.transmission[col] = mean[0] as f32;
                table.transmission_err[col] = err[0] as f32;
            }
        }
        table.build_seconds = start.elapsed().as_secs_f64();
        Ok(table)
    }

    /// Index of node (i, k, m) in `scattered`.
    pub fn index(&self, i: u32, k: u32, m: u32) -> usize {
        let p = &self.params;
        ((m as usize * p.s_bins as usize) + k as usize) * p.theta_bins as usize + i as usize
    }

    /// The scattered value at (θ, s, g), trilinear in index space. s beyond s_max returns
    /// the last column (s = s_max), which is negligible for the default parameters (see
    /// the module documentation); θ and g are clamped to their axes.
    pub fn lookup(&self, theta: f32, s: f32, g: f32) -> f32 {
        let p = &self.params;
        let (x, y, z) = (p.theta_coord(theta), p.s_coord(s), p.g_coord(g));
        let (nt, ns) = (p.theta_bins as usize, p.s_bins as usize);
        let (i0, fi) = split(x, p.theta_bins);
        let (k0, fk) = split(y, p.s_bins);
        let (m0, fm) = split(z, p.g_bins);
        let at = |i: usize, k: usize, m: usize| self.scattered[(m * ns + k) * nt + i];
        let mut v = 0.0;
        for (dm, wm) in [(0, 1.0 - fm), (1, fm)] {
            for (dk, wk) in [(0, 1.0 - fk), (1, fk)] {
                for (di, wi) in [(0, 1.0 - fi), (1, fi)] {
                    let w = wm * wk * wi;
                    if w > 0.0 {
                        v += w * at(i0 + di, k0 + dk, m0 + dm);
                    }
                }
            }
        }
        v
    }

    /// Transmission at (s, g), bilinear in index space; s beyond s_max returns the last
    /// column.
    pub fn transmission_at(&self, s: f32, g: f32) -> f32 {
        let p = &self.params;
        let ns = p.s_bins as usize;
        let (k0, fk) = split(p.s_coord(s), p.s_bins);
        let (m0, fm) = split(p.g_coord(g), p.g_bins);
        let mut v = 0.0;
        for (dm, wm) in [(0, 1.0 - fm), (1, fm)] {
            for (dk, wk) in [(0, 1.0 - fk), (1, fk)] {
                let w = wm * wk;
                if w > 0.0 {
                    v += w * self.transmission[(m0 + dm) * ns + k0 + dk];
                }
            }
        }
        v
    }

    /// The largest standard errors, absolute and relative (over the entries above 1e-3 of
    /// the largest value).
    pub fn errors(&self) -> ErrorSummary {
        let worst = |v: &[f32], e: &[f32]| {
            let max = v.iter().fold(0.0f32, |a, &b| a.max(b));
            let mut rel = 0.0f32;
            let mut abs = 0.0f32;
            for (&x, &s) in v.iter().zip(e) {
                abs = abs.max(s);
                if x > 1e-3 * max && x > 0.0 {
                    rel = rel.max(s / x);
                }
            }
            (max, rel, abs)
        };
        let (scattered_max, scattered_rel, scattered_abs) =
            worst(&self.scattered, &self.scattered_err);
        let (_, transmission_rel, transmission_abs) =
            worst(&self.transmission, &self.transmission_err);
        ErrorSummary {
            scattered_max,
            scattered_rel,
            scattered_abs,
            transmission_rel,
            transmission_abs,
        }
    }
}

/// Lower node and fraction of a continuous index on an axis of n nodes.
fn split(x: f32, n: u32) -> (usize, f32) {
    let i = (x.floor() as usize).min(n as usize - 2);
    (i, (x - i as f32).clamp(0.0, 1.0))
}

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

/// Version of the file format and of the estimator; part of the cache file's name.
/// Version 2: the header ends with a CRC-32 of the rest of the file (issue 33).
pub const FORMAT_VERSION: u32 = 2;
/// The first bytes of every table file: what marks a file as ours.
pub const MAGIC: [u8; 8] = *b"RFKAMBT\0";
/// Bytes before the arrays: magic, version, the parameters, the build's seconds and the
/// checksum.
const HEADER_BYTES: usize = 8 + 4 + 4 + 4 * 3 + 4 + 4 + 8 + 8 + 4;
/// Where the checksum sits: the header's last four bytes.
const CRC_AT: usize = HEADER_BYTES - 4;

/// CRC-32 (IEEE) of a file's bytes without its checksum field: the header before it and
/// every array after it.
fn checksum(bytes: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..CRC_AT]);
    h.update(&bytes[HEADER_BYTES..]);
    h.finalize()
}

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
        ensure!(
            self.s_max.is_finite() && self.s_max > 0.0,
            "s_max {} must be a finite number > 0",
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
        let threads = if threads > 0 {
            threads
        } else {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        }
        .min(units);
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
        let parts: Vec<Vec<Done>> = std::thread::scope(|sc| {
            let handles: Vec<_> = (0..threads).map(|_| sc.spawn(work)).collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("ambient table worker panicked"))
                .collect()
        });
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

    /// Write the table to `path` atomically (a temporary file beside it, then a rename),
    /// making its folder if needed.
    pub fn save(&self, path: &Path) -> Result<()> {
        let p = &self.params;
        let mut bytes = Vec::with_capacity(
            HEADER_BYTES + 4 * (self.scattered.len() * 2 + self.transmission.len() * 2),
        );
        bytes.extend_from_slice(&MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&p.albedo.to_le_bytes());
        for n in [p.theta_bins, p.s_bins, p.g_bins] {
            bytes.extend_from_slice(&n.to_le_bytes());
        }
        bytes.extend_from_slice(&p.s_max.to_le_bytes());
        bytes.extend_from_slice(&p.paths.to_le_bytes());
        bytes.extend_from_slice(&p.seed.to_le_bytes());
        bytes.extend_from_slice(&self.build_seconds.to_le_bytes());
        bytes.extend_from_slice(&[0; 4]); // the checksum, filled in below
        debug_assert_eq!(bytes.len(), HEADER_BYTES);
        for a in [
            &self.scattered,
            &self.scattered_err,
            &self.transmission,
            &self.transmission_err,
        ] {
            for v in a.iter() {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        let crc = checksum(&bytes);
        bytes[CRC_AT..HEADER_BYTES].copy_from_slice(&crc.to_le_bytes());
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        }
        crate::files::write_atomically(path, &bytes)
            .with_context(|| format!("{}: cannot write the ambient table", path.display()))
    }

    /// Read a table written by [`AmbientTable::save`], checking the magic, version,
    /// parameters, size, the checksum (header and arrays) and that every value is finite;
    /// errors name the file and the reason.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path)
            .map_err(|e| anyhow!("{}: cannot read the ambient table: {e}", path.display()))?;
        Self::parse(&bytes)
            .with_context(|| format!("{}: not a usable ambient table", path.display()))
    }

    fn parse(bytes: &[u8]) -> Result<Self> {
        ensure!(
            bytes.len() >= HEADER_BYTES,
            "truncated: {} bytes, shorter than the {HEADER_BYTES}-byte header",
            bytes.len()
        );
        ensure!(
            bytes[..8] == MAGIC,
            "wrong magic (not an ambient table file)"
        );
        let mut at = 8;
        let mut take = |n: usize| {
            let b = &bytes[at..at + n];
            at += n;
            b
        };
        let u32_ = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("4 bytes"));
        let f32_ = |b: &[u8]| f32::from_le_bytes(b.try_into().expect("4 bytes"));
        let version = u32_(take(4));
        ensure!(
            version == FORMAT_VERSION,
            "format version {version}, this build reads version {FORMAT_VERSION}"
        );
        let albedo = f32_(take(4));
        let theta_bins = u32_(take(4));
        let s_bins = u32_(take(4));
        let g_bins = u32_(take(4));
        let s_max = f32_(take(4));
        let paths = u32_(take(4));
        let seed = u64::from_le_bytes(take(8).try_into().expect("8 bytes"));
        let build_seconds = f64::from_le_bytes(take(8).try_into().expect("8 bytes"));
        let stored_crc = u32_(take(4));
        let params = TableParams {
            albedo,
            theta_bins,
            s_bins,
            g_bins,
            s_max,
            paths,
            seed,
        };
        params
            .validate()
            .context("invalid parameters in the header")?;
        let n3 = params.entries();
        let n2 = s_bins as usize * g_bins as usize;
        let expected = HEADER_BYTES + 4 * (2 * n3 + 2 * n2);
        ensure!(
            bytes.len() == expected,
            "{} bytes where parameters {}x{}x{} need {expected} (truncated or padded)",
            bytes.len(),
            theta_bins,
            s_bins,
            g_bins
        );
        let crc = checksum(bytes);
        ensure!(
            crc == stored_crc,
            "corrupt: the payload does not match its checksum (CRC-32 {crc:08x}, the header \
             says {stored_crc:08x})"
        );
        let mut arrays = Vec::with_capacity(4);
        let mut off = HEADER_BYTES;
        for (name, n) in [
            ("scattered", n3),
            ("scattered error", n3),
            ("transmission", n2),
            ("transmission error", n2),
        ] {
            let a: Vec<f32> = bytes[off..off + 4 * n].chunks_exact(4).map(f32_).collect();
            off += 4 * n;
            if let Some(j) = a.iter().position(|v| !v.is_finite()) {
                bail!("{name} value {j} is {} (not finite)", a[j]);
            }
            arrays.push(a);
        }
        let transmission_err = arrays.pop().expect("four arrays");
        let transmission = arrays.pop().expect("four arrays");
        let scattered_err = arrays.pop().expect("four arrays");
        let scattered = arrays.pop().expect("four arrays");
        Ok(Self {
            params,
            scattered,
            scattered_err,
            transmission,
            transmission_err,
            build_seconds,
        })
    }
}

/// The cache folder: `dir` if given, else `$REFRAKT_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/refrakt`, else `$HOME/.cache/refrakt`.
pub fn cache_dir(dir: Option<&Path>) -> Result<PathBuf> {
    if let Some(d) = dir {
        return Ok(d.to_path_buf());
    }
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    if let Some(d) = var("REFRAKT_CACHE_DIR") {
        return Ok(PathBuf::from(d));
    }
    if let Some(d) = var("XDG_CACHE_HOME") {
        return Ok(PathBuf::from(d).join("refrakt"));
    }
    if let Some(h) = var("HOME") {
        return Ok(PathBuf::from(h).join(".cache").join("refrakt"));
    }
    bail!("no cache folder: pass one, or set REFRAKT_CACHE_DIR, XDG_CACHE_HOME or HOME")
}

/// The table of `params` from the cache (see [`cache_dir`]), else built and written there.
/// A corrupt (checksum), truncated or mismatched file is reported in one warning and
/// rebuilt. A table that cannot be written is a warning too, not an error: this is the
/// renderer's implicit cache, and rendering, not caching, is the caller's job (`refrakt
/// precompute ambient`, whose job is the file, checks with [`check_target`] and fails).
pub fn load_or_build(
    params: &TableParams,
    cache_dir: Option<&Path>,
    threads: usize,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(AmbientTable, Source)> {
    params.validate()?;
    let path = self::cache_dir(cache_dir)?.join(params.file_name());
    if path.exists() {
        match AmbientTable::load(&path) {
            Ok(t) if t.params == *params => return Ok((t, Source::Cached(path))),
            Ok(t) => log::warn!(
                "{}: made with other parameters ({}); rebuilding",
                path.display(),
                t.params.differences(params)
            ),
            Err(e) => log::warn!("{e:#}; rebuilding"),
        }
    }
    let table = AmbientTable::build(params, threads, progress)?;
    let written = match table.save(&path) {
        Ok(()) => Some(path),
        Err(e) => {
            log::warn!("{e:#}; the table is not cached");
            None
        }
    };
    let seconds = table.build_seconds;
    Ok((table, Source::Built { seconds, written }))
}

/// What [`check_target`] found at a table's path.
#[derive(Debug)]
pub enum Existing {
    /// No file: it will be made.
    Nothing,
    /// An intact table of the parameters asked for.
    Table(AmbientTable),
    /// An ambient table file (it starts with [`MAGIC`]) that is not usable for these
    /// parameters, and why: other parameters, another format version, a checksum
    /// mismatch, truncated (the reason, without the file's name). Ours to replace.
    Stale(String),
    /// A file that is not an ambient table (no [`MAGIC`]): someone else's.
    Foreign,
}

/// Checks, before a (long) build, that a table for `params` can be written to `path`
/// and says what is there now: an error if `path` is a folder, a link to nothing, or in
/// a folder that cannot be created or written to (a probe file is made and removed).
/// Links are followed (the table replaces the file a link points to).
pub fn check_target(params: &TableParams, path: &Path) -> Result<Existing> {
    let target = crate::files::resolve(path)?;
    let existing = match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => bail!("{}: is a folder; give a file name", path.display()),
        // A device or FIFO: never a table (not read: a FIFO would block).
        Ok(m) if !m.is_file() => Existing::Foreign,
        Ok(_) => {
            use std::io::Read as _;
            let mut head = Vec::with_capacity(MAGIC.len());
            std::fs::File::open(&target)
                .and_then(|f| f.take(MAGIC.len() as u64).read_to_end(&mut head))
                .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
            if head != MAGIC {
                Existing::Foreign
            } else {
                let bytes = std::fs::read(&target)
                    .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
                match AmbientTable::parse(&bytes) {
                    Ok(t) if t.params == *params => Existing::Table(t),
                    Ok(t) => Existing::Stale(format!(
                        "a table made with other parameters ({})",
                        t.params.differences(params)
                    )),
                    Err(e) => Existing::Stale(format!("{e:#}")),
                }
            }
        }
        Err(e)
            if matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            Existing::Nothing
        }
        Err(e) => bail!("{}: {e}", path.display()),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| {
        // A file where a folder should be: name it.
        match dir.ancestors().find(|a| a.is_file()) {
            Some(f) => anyhow!(
                "{}: cannot create the folder {}: {} is a file",
                path.display(),
                dir.display(),
                f.display()
            ),
            None => anyhow!(
                "{}: cannot create the folder {}: {e}",
                path.display(),
                dir.display()
            ),
        }
    })?;
    // The folder can be written (tried), as every output is checked.
    crate::files::check_writable(path)?;
    Ok(existing)
}

/// Lower node and fraction of a continuous index on an axis of n nodes.
fn split(x: f32, n: u32) -> (usize, f32) {
    let i = (x.floor() as usize).min(n as usize - 2);
    (i, (x - i as f32).clamp(0.0, 1.0))
}

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
struct Walk {
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
fn scattered_column(params: &TableParams, s: f64, g: f64, walk: &mut Walk) -> (Vec<f64>, Vec<f64>) {
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
fn transmission_entry(params: &TableParams, s: f64, g: f64, walk: &mut Walk) -> (f64, f64) {
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

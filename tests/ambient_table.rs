//! The ambient-scattering light-transport table (src/render/ambient/table/): limits,
//! symmetries and energy, an independent forward photon tracer, reproducibility, the disk
//! cache and `refrakt precompute ambient`. CPU only; small tables.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use refrakt::render::ambient::table::{
    self, phase_hg, AmbientTable, Source, TableParams, FORMAT_VERSION,
};

fn no_progress(_: u64, _: u64) {}

fn build(p: &TableParams) -> AmbientTable {
    AmbientTable::build(p, 0, &no_progress).expect("building the table")
}

fn small(
    albedo: f32,
    theta_bins: u32,
    s_bins: u32,
    g_bins: u32,
    s_max: f32,
    paths: u32,
) -> TableParams {
    TableParams {
        albedo,
        theta_bins,
        s_bins,
        g_bins,
        s_max,
        paths,
        seed: 7,
    }
}

/// Node index of g on the axis, asserting it is a node.
fn g_node(p: &TableParams, g: f64) -> u32 {
    let m = (0..p.g_bins)
        .min_by(|&a, &b| (p.g(a) - g).abs().total_cmp(&(p.g(b) - g).abs()))
        .unwrap();
    assert!(
        (p.g(m) - g).abs() < 1e-6,
        "g {g} is not a node ({})",
        p.g(m)
    );
    m
}

fn s_node(p: &TableParams, s: f64) -> u32 {
    let k = (0..p.s_bins)
        .min_by(|&a, &b| (p.s(a) - s).abs().total_cmp(&(p.s(b) - s).abs()))
        .unwrap();
    assert!(
        (p.s(k) - s).abs() < 1e-6,
        "s {s} is not a node ({})",
        p.s(k)
    );
    k
}

#[test]
fn axes_coordinates_and_lookup_hit_the_nodes() {
    let p = small(0.9, 5, 4, 5, 63.0, 64); // s nodes 64^(k/3) - 1 = 0, 3, 15, 63
    assert_eq!(p.theta_coord(0.0), 0.0);
    assert!((p.theta_coord(std::f32::consts::FRAC_PI_2) - 2.0).abs() < 1e-6);
    assert_eq!(p.s_coord(0.0), 0.0);
    assert!((p.s_coord(3.0) - 1.0).abs() < 1e-5);
    assert!((p.s_coord(15.0) - 2.0).abs() < 1e-5);
    assert_eq!(p.s_coord(100.0), 3.0, "beyond s_max: the last column");
    assert!((p.g_coord(0.0) - 2.0).abs() < 1e-6);
    assert_eq!(p.g_coord(-0.99), 0.0);
    let t = build(&p);
    for m in 0..p.g_bins {
        for k in 0..p.s_bins {
            for i in 0..p.theta_bins {
                let v = t.lookup(p.theta(i) as f32, p.s(k) as f32, p.g(m) as f32);
                let want = t.scattered[t.index(i, k, m)];
                assert!(
                    (v - want).abs() <= 1e-5 * want.abs().max(1e-6),
                    "{v} vs {want}"
                );
            }
            let tr = t.transmission_at(p.s(k) as f32, p.g(m) as f32);
            let want = t.transmission[(m * p.s_bins + k) as usize];
            assert!((tr - want).abs() <= 1e-6, "{tr} vs {want}");
        }
    }
    // Halfway between two θ nodes: the mean of the two.
    let (a, b) = (t.scattered[t.index(1, 2, 1)], t.scattered[t.index(2, 2, 1)]);
    let mid = t.lookup(
        (p.theta(1) + p.theta(2)) as f32 / 2.0,
        p.s(2) as f32,
        p.g(1) as f32,
    );
    assert!(
        (mid - (a + b) / 2.0).abs() <= 1e-5 * a.max(b),
        "{mid} vs {a}, {b}"
    );
}

/// At s = 0 nothing scatters: scattered 0 and transmission 1 exactly. At small s only
/// one interaction counts to first order: the first vertex lies within the unit distance to
/// the surface with probability 1 − e^{−s}; its next-event term is Λ·P_HG(cos) e^{−s d}
/// with d ≤ 2, and averaged over ω' ~ HG(g) about ω_o the phase function toward +z is the
/// convolution of two HG lobes, HG with g² (exact for Henyey–Greenstein). Walks with two
/// or more vertices need another interaction within a chord ≤ 2 (probability ≤ q =
/// 1 − e^{−2s} each) and carry at most Λ²·P_max, P_max = (1+|g|)/(1−|g|)². So
/// e^{−2s}(1−e^{−s})ΛP_{g²}(cos θ) ≤ scattered ≤ (1−e^{−s})[ΛP_{g²}(cos θ) + P_max q/(1−q)].
#[test]
fn small_extinction_is_first_order() {
    let p = small(0.9, 5, 3, 5, 0.04, 40_000); // s = 0, 0.01, 0.04; g = 0, ±0.495, ±0.99
    let t = build(&p);
    let lambda = p.albedo as f64;
    for m in 0..p.g_bins {
        assert_eq!(t.transmission[(m * p.s_bins) as usize], 1.0);
        for i in 0..p.theta_bins {
            assert_eq!(t.scattered[t.index(i, 0, m)], 0.0);
            assert_eq!(t.scattered_err[t.index(i, 0, m)], 0.0);
        }
    }
    for m in 1..p.g_bins - 1 {
        let g = p.g(m);
        let pmax = (1.0 + g.abs()) / (1.0 - g.abs()).powi(2);
        for k in 1..p.s_bins {
            let s = p.s(k);
            let q = 1.0 - (-2.0 * s).exp();
            for i in 0..p.theta_bins {
                let j = t.index(i, k, m);
                let (v, e) = (t.scattered[j] as f64, t.scattered_err[j] as f64);
                let first = (1.0 - (-s).exp()) * lambda * phase_hg(p.theta(i).cos(), g * g);
                let lo = (-2.0 * s).exp() * first - 4.0 * e;
                let hi = first + (1.0 - (-s).exp()) * pmax * q / (1.0 - q) + 4.0 * e;
                assert!(
                    lo <= v && v <= hi,
                    "s {s}, g {g}, θ {}: {v} ± {e} outside [{lo}, {hi}] (first order {first})",
                    p.theta(i)
                );
                assert!(e < 0.1 * first, "s {s}, g {g}: error {e} of {first}");
            }
        }
    }
}

#[test]
fn no_albedo_means_no_scattering() {
    let p = small(0.0, 3, 4, 3, 4.0, 256);
    let t = build(&p);
    assert!(t.scattered.iter().all(|&v| v == 0.0));
    assert!(t.scattered_err.iter().all(|&v| v == 0.0));
    for m in 0..p.g_bins {
        for k in 0..p.s_bins {
            let j = (m * p.s_bins + k) as usize;
            assert_eq!(t.transmission[j], (-2.0 * p.s(k)).exp() as f32);
            assert_eq!(t.transmission_err[j], 0.0);
        }
    }
}

#[test]
fn isotropic_scattering_is_independent_of_the_angle() {
    let p = small(0.9, 9, 4, 3, 9.0, 4096);
    let t = build(&p);
    let m = g_node(&p, 0.0);
    for k in 1..p.s_bins {
        let j0 = t.index(0, k, m);
        let (v0, e0) = (t.scattered[j0], t.scattered_err[j0]);
        assert!(v0 > 0.0);
        for i in 1..p.theta_bins {
            let j = t.index(i, k, m);
            let (v, e) = (t.scattered[j], t.scattered_err[j]);
            let tol = 4.0 * (e * e + e0 * e0).sqrt();
            assert!(
                (v - v0).abs() <= tol,
                "s {}: θ {} gives {v}, θ 0 gives {v0} (tolerance {tol})",
                p.s(k),
                p.theta(i)
            );
        }
    }
    // Anisotropic scattering does depend on it (the test can tell).
    let m = p.g_bins - 1;
    let (a, b) = (t.scattered[t.index(0, 1, m)], t.scattered[t.index(8, 1, m)]);
    assert!(a > 3.0 * b, "g = 0.99: forward {a}, backward {b}");
}

/// Energy. Transmission is at most 1 and grows with the albedo. For Λ = 1 and g = 0 the
/// fluence at the centre is exactly 1 per unit incident irradiance for every s: the centre
/// sees the same for a beam from any direction (the sphere's symmetry), so it equals the
/// fluence under an isotropic mixture of unit beams, i.e. uniform incident radiance 1/(4π);
/// in a non-absorbing medium that radiance is the solution everywhere inside, fluence
/// 4π·1/(4π) = 1. With absorption (Λ < 1) it is less.
#[test]
fn energy() {
    let tables: Vec<AmbientTable> = [0.5, 0.9, 1.0]
        .iter()
        .map(|&a| build(&small(a, 3, 5, 3, 4.0, 8192)))
        .collect();
    for t in &tables {
        let p = &t.params;
        for (j, (&v, &e)) in t.transmission.iter().zip(&t.transmission_err).enumerate() {
            assert!(
                v <= 1.0 + 4.0 * e,
                "Λ {}: transmission[{j}] = {v} ± {e}",
                p.albedo
            );
        }
    }
    for w in tables.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        for j in 0..a.transmission.len() {
            let k = j as u32 % a.params.s_bins;
            if k == 0 {
                continue;
            }
            let (va, vb) = (a.transmission[j], b.transmission[j]);
            let tol = 4.0 * a.transmission_err[j].hypot(b.transmission_err[j]);
            assert!(
                vb > va - tol,
                "entry {j}: Λ {} gives {va}, Λ {} gives {vb}",
                a.params.albedo,
                b.params.albedo
            );
        }
    }
    // And in sum, strictly (common random numbers: the same walks for every albedo).
    let sums: Vec<f32> = tables.iter().map(|t| t.transmission.iter().sum()).collect();
    assert!(sums[0] < sums[1] && sums[1] < sums[2], "{sums:?}");
    for t in &tables {
        let p = &t.params;
        let m = g_node(p, 0.0);
        for k in 1..p.s_bins {
            let s = p.s(k);
            for i in 0..p.theta_bins {
                let j = t.index(i, k, m);
                let total = (-s).exp() + t.scattered[j] as f64;
                let e = 4.0 * t.scattered_err[j] as f64;
                if p.albedo == 1.0 {
                    assert!(
                        (total - 1.0).abs() <= e,
                        "Λ = 1, s {s}: centre fluence {total} ± {e}, must be 1"
                    );
                } else {
                    assert!(
                        total < 1.0 + e,
                        "Λ {}, s {s}: centre fluence {total}",
                        p.albedo
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// An independent forward photon tracer.

/// PCG32 (O'Neill), not the table's generator.
struct Pcg(u64);

impl Pcg {
    fn next(&mut self) -> f64 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        let r = (old >> 59) as u32;
        (x.rotate_right(r) as f64 + 0.5) / 4294967296.0
    }
}

#[derive(Default)]
struct Tally {
    sum: f64,
    sq: f64,
}

impl Tally {
    fn add(&mut self, x: f64) {
        self.sum += x;
        self.sq += x * x;
    }

    /// Mean and standard error over n photons.
    fn result(&self, n: u64) -> (f64, f64) {
        let n = n as f64;
        let mean = self.sum / n;
        (
            mean,
            ((self.sq / n - mean * mean).max(0.0) / (n - 1.0)).sqrt(),
        )
    }
}

struct Forward {
    ball_direct: (f64, f64),
    ball_scattered: (f64, f64),
    cap_direct: (f64, f64),
    cap_scattered: (f64, f64),
}

/// Photons uniform on the unit disk, travelling +z into the sphere (total power π for unit
/// irradiance), analog flights with the albedo as a weight and Russian roulette; the
/// track-length fluence in the ball of radius `ball` at the centre and the power leaving
/// through the cap of half-angle `cap` around the far pole per cap area, each split into
/// unscattered and scattered photons.
fn forward(s: f64, g: f64, albedo: f64, photons: u64, ball: f64, cap: f64, seed: u64) -> Forward {
    let mut rng = Pcg(seed.wrapping_mul(0x9E3779B97F4A7C15) | 1);
    let ball_volume = 4.0 / 3.0 * PI * ball.powi(3);
    let cap_area = 2.0 * PI * (1.0 - cap.cos());
    let power = PI; // per photon, before dividing by the photon count (in the mean)
    let (mut bd, mut bs, mut cd, mut cs) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    for _ in 0..photons {
        let r = rng.next().sqrt();
        let phi = 2.0 * PI * rng.next();
        let mut p = [r * phi.cos(), r * phi.sin(), -(1.0 - r * r).sqrt()];
        let mut d = [0.0, 0.0, 1.0];
        let mut w = 1.0;
        let mut scattered = false;
        let (mut track_d, mut track_s, mut out_d, mut out_s) = (0.0, 0.0, 0.0, 0.0);
        loop {
            let b = p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
            let pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            let exit = -b + (b * b - (pp - 1.0)).max(0.0).sqrt();
            let flight = -rng.next().ln() / s;
            let len = flight.min(exit);
            // The segment's chord in the ball.
            let disc = b * b - (pp - ball * ball);
            if disc > 0.0 {
                let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
                let inside = (t1.min(len) - t0.max(0.0)).max(0.0);
                if scattered {
                    track_s += w * inside;
                } else {
                    track_d += w * inside;
                }
            }
            if flight >= exit {
                let z = p[2] + d[2] * exit;
                if z >= cap.cos() {
                    if scattered {
                        out_s += w;
                    } else {
                        out_d += w;
                    }
                }
                break;
            }
            for a in 0..3 {
                p[a] += d[a] * flight;
            }
            w *= albedo;
            if w == 0.0 {
                break;
            }
            if w < 0.1 {
                if rng.next() >= w / 0.1 {
                    break;
                }
                w = 0.1;
            }
            scattered = true;
            // A new direction at HG cosine c about d.
            let xi = rng.next();
            let c = if g.abs() < 1e-6 {
                1.0 - 2.0 * xi
            } else {
                let q = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
                ((1.0 + g * g - q * q) / (2.0 * g)).clamp(-1.0, 1.0)
            };
            let psi = 2.0 * PI * rng.next();
            // Any unit vector perpendicular to d, then the second by a cross product.
            let u = if d[0].abs() < 0.9 {
                normalise(cross(d, [1.0, 0.0, 0.0]))
            } else {
                normalise(cross(d, [0.0, 1.0, 0.0]))
            };
            let v = cross(d, u);
            let st = (1.0 - c * c).max(0.0).sqrt();
            for a in 0..3 {
                d[a] = c * d[a] + st * (psi.cos() * u[a] + psi.sin() * v[a]);
            }
            d = normalise(d);
        }
        bd.add(power * track_d / ball_volume);
        bs.add(power * track_s / ball_volume);
        cd.add(power * out_d / cap_area);
        cs.add(power * out_s / cap_area);
    }
    Forward {
        ball_direct: bd.result(photons),
        ball_scattered: bs.result(photons),
        cap_direct: cd.result(photons),
        cap_scattered: cs.result(photons),
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalise(a: [f64; 3]) -> [f64; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// The ball average of the direct beam's fluence e^{−s d(y)}: cylindrical shells, the
/// integral along z in closed form.
fn ball_direct(s: f64, ball: f64) -> f64 {
    let n = 4000;
    let mut sum = 0.0;
    for j in 0..n {
        let rho = (j as f64 + 0.5) / n as f64 * ball;
        let h = (ball * ball - rho * rho).sqrt();
        sum += 2.0 * PI * rho * (-s * (1.0 - rho * rho).sqrt()).exp() * 2.0 * (s * h).sinh() / s;
    }
    sum * ball / n as f64 / (4.0 / 3.0 * PI * ball.powi(3))
}

/// The cap average of the direct beam's exit irradiance: 2π∫_{cos α}^1 e^{−2su} u du / area.
fn cap_direct(s: f64, cap: f64) -> f64 {
    let a = 2.0 * s;
    let prim = |u: f64| -(-a * u).exp() * (u / a + 1.0 / (a * a));
    2.0 * PI * (prim(1.0) - prim(cap.cos())) / (2.0 * PI * (1.0 - cap.cos()))
}

/// The table against the forward tracer. The forward tracer's unscattered tallies must
/// match their closed forms (checks the tracer); its scattered tallies are compared with
/// the table's scattered parts, with both standard errors (4σ) and a bound on the bias of
/// averaging over the ball of radius b and the cap of half-angle α: a smooth field f
/// averages over a ball to f(0) + (b²/10)∇²f + O(b⁴); the scattered field varies on the
/// scales of the mean free path 1/s and of the radius, so |∇²f| ≤ (s² + 2)·f, bias ≤
/// b²(s² + 2)/10·f. Over a cap, the irradiance at polar angle β is E(0) + E₂β² with
/// ⟨β²⟩ = α²/2 and |E₂| ≤ (1 + s)·E(0) on the same grounds (the cosine to +z of the cap's
/// normal, 1 − β²/2, is of the same order): bias ≤ α²(1 + s)/2·E.
#[test]
fn agrees_with_a_forward_photon_tracer() {
    let (ball, cap, photons) = (0.12, 0.15, 1_000_000);
    // s nodes 16^(k/4) - 1 = 0, 1, 3, 7, 15; g nodes every 0.09 from −0.99 (−0.45, 0, 0.81 among them).
    let p = small(0.9, 3, 5, 23, 15.0, 16_384);
    let t = build(&p);
    let conservative = small(1.0, 3, 5, 3, 15.0, 16_384);
    let tc = build(&conservative);
    let mut report = Vec::new();
    let mut failures = Vec::new();
    let mut seed = 11;
    for (tab, gs) in [(&t, &[-0.45, 0.0, 0.81][..]), (&tc, &[0.0][..])] {
        let tp = &tab.params;
        for &g in gs {
            let m = g_node(tp, g);
            for s in [1.0, 3.0] {
                let k = s_node(tp, s);
                seed += 1;
                let f = forward(s, g, tp.albedo as f64, photons, ball, cap, seed);
                // The tracer's direct tallies against their closed forms.
                let (bd, bd_e) = f.ball_direct;
                let want = ball_direct(s, ball);
                if (bd - want).abs() > 4.0 * bd_e {
                    failures.push(format!(
                        "forward ball direct s {s}: {bd} ± {bd_e} vs {want}"
                    ));
                }
                let (cd, cd_e) = f.cap_direct;
                let want = cap_direct(s, cap);
                // Few photons get through unscattered at s = 4: the error the expected
                // value implies (a photon adds π/A with probability want·A/π).
                let x = PI / (2.0 * PI * (1.0 - cap.cos()));
                let cd_e = cd_e.max(((x * want - want * want) / photons as f64).sqrt());
                if (cd - want).abs() > 4.0 * cd_e {
                    failures.push(format!("forward cap direct s {s}: {cd} ± {cd_e} vs {want}"));
                }
                // (b) transmission at the pole.
                let j = (m * tp.s_bins + k) as usize;
                let tr = tab.transmission[j] as f64 - (-2.0 * s).exp();
                let tr_e = tab.transmission_err[j] as f64;
                let (cs, cs_e) = f.cap_scattered;
                let tol = 4.0 * tr_e.hypot(cs_e) + cap * cap * (1.0 + s) / 2.0 * tr;
                let line = format!(
                    "Λ {} s {s} g {g}: pole scattered table {tr:.5} ± {tr_e:.5}, forward {cs:.5} \
                     ± {cs_e:.5} (tolerance {tol:.5})",
                    tp.albedo
                );
                if (tr - cs).abs() > tol {
                    failures.push(line.clone());
                }
                report.push(line);
                // (a) the fluence at the centre (the table is the fluence for g = 0).
                if g == 0.0 {
                    let n = tp.theta_bins;
                    let v = (0..n)
                        .map(|i| tab.scattered[tab.index(i, k, m)] as f64)
                        .sum::<f64>()
                        / n as f64;
                    let v_e = (0..n)
                        .map(|i| tab.scattered_err[tab.index(i, k, m)] as f64)
                        .fold(0.0, f64::max);
                    let (bs, bs_e) = f.ball_scattered;
                    let tol = 4.0 * v_e.hypot(bs_e) + ball * ball * (s * s + 2.0) / 10.0 * v;
                    let line = format!(
                        "Λ {} s {s}: centre fluence table e^-s + {v:.5} ± {v_e:.5}, forward \
                         {bd:.5} + {bs:.5} ± {bs_e:.5} (tolerance {tol:.5})",
                        tp.albedo
                    );
                    if (v - bs).abs() > tol {
                        failures.push(line.clone());
                    }
                    report.push(line);
                }
            }
        }
    }
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------------
// Reproducibility and the cache.

#[test]
fn bit_identical_for_any_thread_count() {
    let p = small(0.9, 4, 4, 3, 16.0, 300);
    let a = AmbientTable::build(&p, 1, &no_progress).unwrap();
    let b = AmbientTable::build(&p, 3, &no_progress).unwrap();
    assert_eq!(a.scattered, b.scattered);
    assert_eq!(a.scattered_err, b.scattered_err);
    assert_eq!(a.transmission, b.transmission);
    assert_eq!(a.transmission_err, b.transmission_err);
    // Another seed gives another table.
    let c = build(&TableParams { seed: 8, ..p });
    assert_ne!(a.scattered, c.scattered);
}

#[test]
fn save_load_corrupt_files_and_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let p = small(0.9, 3, 3, 3, 4.0, 200);
    let calls = std::sync::atomic::AtomicU64::new(0);
    let progress = |done: u64, total: u64| {
        assert!(done <= total);
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    };
    let (t, src) = table::load_or_build(&p, Some(dir.path()), 2, &progress).unwrap();
    let file = dir.path().join(p.file_name());
    assert!(p.file_name().ends_with(&format!("-v{FORMAT_VERSION}.bin")));
    assert!(
        matches!(&src, Source::Built { written: Some(f), .. } if *f == file),
        "{src:?}"
    );
    assert_eq!(calls.load(std::sync::atomic::Ordering::Relaxed), 18);
    assert!(t.build_seconds > 0.0);
    // Round trip.
    assert_eq!(AmbientTable::load(&file).unwrap(), t);
    let (t2, src) = table::load_or_build(&p, Some(dir.path()), 2, &no_progress).unwrap();
    assert_eq!(src, Source::Cached(file.clone()));
    assert_eq!(t2, t);
    // Explicit save elsewhere.
    let other = dir.path().join("sub/other.bin");
    t.save(&other).unwrap();
    assert_eq!(AmbientTable::load(&other).unwrap(), t);

    let bytes = std::fs::read(&file).unwrap();
    let corrupt = |what: &str, data: &[u8], reason: &str| {
        std::fs::write(&file, data).unwrap();
        let e = format!("{:#}", AmbientTable::load(&file).unwrap_err());
        assert!(e.contains(&file.display().to_string()), "{what}: {e}");
        assert!(e.contains(reason), "{what}: {e}");
        let (t3, src) = table::load_or_build(&p, Some(dir.path()), 2, &no_progress).unwrap();
        assert!(matches!(src, Source::Built { .. }), "{what}: {src:?}");
        assert_eq!(t3.scattered, t.scattered, "{what}");
        assert_eq!(
            AmbientTable::load(&file).unwrap().scattered,
            t.scattered,
            "{what}: rewritten"
        );
    };
    corrupt("truncated", &bytes[..bytes.len() - 10], "truncated");
    corrupt("header only", &bytes[..20], "truncated");
    let mut magic = bytes.clone();
    magic[0] = b'X';
    corrupt("wrong magic", &magic, "magic");
    let mut version = bytes.clone();
    version[8] = version[8].wrapping_add(1);
    corrupt("other version", &version, "version");
    let mut nan = bytes.clone();
    let n = nan.len();
    nan[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
    // Caught by the checksum (format version 2) before the finiteness check.
    corrupt("not finite", &nan, "does not match its checksum");
    // A file of other parameters under this name is rebuilt too.
    let q = TableParams { seed: 99, ..p };
    build(&q).save(&file).unwrap();
    let (_, src) = table::load_or_build(&p, Some(dir.path()), 2, &no_progress).unwrap();
    assert!(matches!(src, Source::Built { .. }));
    // A missing file is an error naming it.
    let missing = dir.path().join("missing.bin");
    let e = format!("{:#}", AmbientTable::load(&missing).unwrap_err());
    assert!(e.contains("missing.bin"), "{e}");
}

#[test]
fn params_are_validated() {
    let d = TableParams::default();
    assert!(d.validate().is_ok());
    for (p, what) in [
        (TableParams { albedo: 1.5, ..d }, "albedo"),
        (
            TableParams {
                albedo: f32::NAN,
                ..d
            },
            "albedo",
        ),
        (TableParams { theta_bins: 1, ..d }, "theta bins"),
        (TableParams { s_bins: 0, ..d }, "extinction bins"),
        (TableParams { g_bins: 1, ..d }, "g bins"),
        (TableParams { s_max: 0.0, ..d }, "s_max"),
        (
            TableParams {
                s_max: f32::INFINITY,
                ..d
            },
            "s_max",
        ),
        (
            TableParams { s_max: 1e30, ..d },
            "s_max 1000000000000000000000000000000 must",
        ),
        (TableParams { paths: 0, ..d }, "paths"),
    ] {
        let e = format!("{:#}", p.validate().unwrap_err());
        assert!(e.contains(what), "{what}: {e}");
        assert!(AmbientTable::build(&p, 1, &no_progress).is_err());
    }
}

// ---------------------------------------------------------------------------------------
// The command line.

fn precompute(args: &[&str], cache: &Path) -> std::process::Output {
    let mut all = vec!["precompute", "ambient"];
    all.extend_from_slice(args);
    let dir = cache.to_str().unwrap();
    all.extend_from_slice(&["--cache-dir", dir]);
    common::refrakt(&all)
}

#[test]
fn cli_builds_then_finds_the_table_and_refuses_bad_params() {
    let dir = tempfile::tempdir().unwrap();
    let small = [
        "--theta-bins",
        "3",
        "--extinction-bins",
        "3",
        "--g-bins",
        "3",
        "--paths",
        "64",
        "--threads",
        "2",
    ];
    let out = precompute(&small, dir.path());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("built in"), "{stdout}");
    assert!(stdout.contains("with 2 threads"), "{stdout}");
    assert!(stdout.contains("largest relative std error"), "{stdout}");
    assert!(stdout.contains("largest absolute std error"), "{stdout}");
    assert!(stdout.contains("transmission:"), "{stdout}");
    let file = dir.path().join(
        TableParams {
            theta_bins: 3,
            s_bins: 3,
            g_bins: 3,
            paths: 64,
            ..TableParams::default()
        }
        .file_name(),
    );
    assert!(stdout.contains(&file.display().to_string()), "{stdout}");
    assert!(AmbientTable::load(&file).is_ok());

    let out = precompute(&small, dir.path());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("found cached"), "{stdout}");
    assert!(stdout.contains("largest relative std error"), "{stdout}");

    let mut forced = small.to_vec();
    forced.push("--force");
    let out = precompute(&forced, dir.path());
    assert!(String::from_utf8_lossy(&out.stdout).contains("built in"));

    let target = dir.path().join("elsewhere/table.bin");
    let mut to_file = small.to_vec();
    to_file.extend_from_slice(&["--out", target.to_str().unwrap()]);
    let out = precompute(&to_file, dir.path());
    assert!(out.status.success());
    assert!(AmbientTable::load(&target).is_ok());

    let out = precompute(&["--albedo", "1.5"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_ne!(out.status.code(), None, "killed by a signal: {stderr}");
    assert!(stderr.contains("albedo 1.5 must lie in [0, 1]"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let out = precompute(&["--paths", "0"], dir.path());
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("paths"));
}

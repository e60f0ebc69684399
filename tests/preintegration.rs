//! Issue 3: transfer functions and the GPU preintegration table, checked against an
//! independent CPU quadrature of the continuous integrals (eqs. 3.17, 4.14-4.16) and
//! against closed forms, plus the artefact preintegration exists to remove (Fig. 3.5).

mod common;

use common::*;
use refrakt::render::{Model, RenderOptions, Renderer, TABLE_SIZE};
use refrakt::transfer::TransferFunctions;
use refrakt::volume::{procedural, Volume, Voxels};

const N: usize = TABLE_SIZE as usize;

fn tf(text: &str) -> TransferFunctions {
    TransferFunctions::parse(text, "test").unwrap()
}

/// The continuous segment integrals for one reference step with the scalar going linearly
/// from `front` to `back`, by a fine midpoint rule in f64:
///   σ(s) = -ln(1 - α_tf(s))                       (extinction per reference step, eq. 3.8)
///   A = 1 - exp(-∫σ dλ)                           (eq. 3.17)
///   M = exp(∫ ln m_tf dλ)                          (multiplicative integral, eqs. 4.14-4.15)
///   C = ∫ c_tf σ exp(-∫_0^λ σ) M(0,λ) dλ            (eq. 4.16)
fn cpu_segment(
    tf: &TransferFunctions,
    front: f64,
    back: f64,
    steps: usize,
) -> ([f64; 4], [f64; 3]) {
    let h = 1.0 / steps as f64;
    let (mut tau, mut ln_m) = (0.0f64, [0.0f64; 3]);
    let mut c = [0.0f64; 3];
    for k in 0..steps {
        let lambda = (k as f64 + 0.5) * h;
        let s = (front + (back - front) * lambda) as f32;
        let alpha = tf.opacity.eval(s)[0] as f64;
        let sigma = -(1.0 - alpha).max(1e-300).ln();
        let col = tf.colour.eval(s);
        let med = tf.medium.eval(s);
        let t_mid = (-(tau + 0.5 * sigma * h)).exp();
        for i in 0..3 {
            let m_mid = (ln_m[i] + 0.5 * (med[i] as f64).max(1e-300).ln() * h).exp();
            c[i] += col[i] as f64 * sigma * t_mid * m_mid * h;
            ln_m[i] += (med[i] as f64).max(1e-300).ln() * h;
        }
        tau += sigma * h;
    }
    (
        [c[0], c[1], c[2], 1.0 - (-tau).exp()],
        [ln_m[0].exp(), ln_m[1].exp(), ln_m[2].exp()],
    )
}

fn gpu_table(ctx: &refrakt::vk::Context, tf: &TransferFunctions) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let vol = procedural::slab([4, 4, 4], 0.0).unwrap();
    let mut r = Renderer::new(ctx, &vol, tf).unwrap();
    r.update_preintegration().unwrap();
    r.preintegration().read(ctx).unwrap()
}

fn spike_tf() -> TransferFunctions {
    tf(r#"
colour = [[0.0, 1.0, 0.2, 0.1], [1.0, 0.2, 0.4, 1.0]]
opacity = [[0.0, 0.0], [0.47, 0.0], [0.5, 0.8], [0.53, 0.0], [1.0, 0.0]]
"#)
}

fn medium_step_tf() -> TransferFunctions {
    tf(r#"
colour = [[0.0, 0.9, 0.9, 0.9]]
opacity = [[0.0, 0.1]]
medium = [[0.0, 1.0, 1.0, 1.0], [0.5, 1.0, 1.0, 1.0], [0.5, 0.3, 0.6, 0.9], [1.0, 0.3, 0.6, 0.9]]
"#)
}

fn mixed_tf() -> TransferFunctions {
    let mut t = TransferFunctions::load("ct-bone").unwrap();
    t.medium =
        refrakt::transfer::Piecewise::new(vec![(0.0, [1.0, 1.0, 1.0]), (1.0, [0.5, 0.8, 0.95])]);
    t
}

#[test]
fn gpu_table_matches_cpu_quadrature() {
    with_context(|ctx| {
        for (name, tf) in [
            ("spike", spike_tf()),
            ("medium step", medium_step_tf()),
            ("mixed", mixed_tf()),
        ] {
            let (l0, l1) = gpu_table(ctx, &tf);
            let mut worst = 0.0f64;
            let mut at = (0, 0);
            // Every 5th entry plus the last row/column, and the band around the spike.
            let idx: Vec<usize> = (0..N)
                .filter(|i| i % 5 == 0 || *i == N - 1 || (118..=138).contains(i))
                .collect();
            for &b in &idx {
                for &f in idx.iter().step_by(2) {
                    let (ca, m) = cpu_segment(&tf, f as f64 / 255.0, b as f64 / 255.0, 4096);
                    let g0 = l0[b * N + f];
                    let g1 = l1[b * N + f];
                    for i in 0..4 {
                        let e = (g0[i] as f64 - ca[i]).abs();
                        if e > worst {
                            worst = e;
                            at = (f, b);
                        }
                    }
                    for i in 0..3 {
                        let e = (g1[i] as f64 - m[i]).abs();
                        if e > worst {
                            worst = e;
                            at = (f, b);
                        }
                    }
                }
            }
            println!("{name}: max |GPU - CPU| = {worst:.2e} at (front, back) = {at:?}");
            assert!(worst <= 1e-3, "{name}: max error {worst} at {at:?}");
        }
    });
}

#[test]
fn diagonal_entries_are_the_plain_transfer_function() {
    with_context(|ctx| {
        let tf = tf(r#"
colour = [[0.0, 0.1, 0.5, 0.9], [1.0, 0.9, 0.3, 0.2]]
opacity = [[0.0, 0.0], [0.6, 0.7], [1.0, 0.3]]
medium = [[0.0, 1.0, 0.9, 0.8], [1.0, 0.4, 0.5, 0.6]]
"#);
        let (l0, l1) = gpu_table(ctx, &tf);
        for i in 0..N {
            let s = i as f32 / 255.0;
            let a = tf.opacity.eval(s)[0];
            let m = tf.medium.eval(s);
            let g0 = l0[i * N + i];
            let g1 = l1[i * N + i];
            // Opacity corrected to the reference distance is the TF itself (eq. 3.13, ratio 1).
            assert!((g0[3] - a).abs() < 1e-4, "s={s}: alpha {} vs {a}", g0[3]);
            for k in 0..3 {
                assert!(
                    (g1[k] - m[k]).abs() < 1e-4,
                    "s={s}: medium {} vs {}",
                    g1[k],
                    m[k]
                );
            }
        }
        // With a white medium the premultiplied colour is c * alpha.
        let mut white = tf.clone();
        white.medium = refrakt::transfer::Piecewise::constant([1.0; 3]);
        let (l0, _) = gpu_table(ctx, &white);
        for i in 0..N {
            let s = i as f32 / 255.0;
            let (a, c) = (white.opacity.eval(s)[0], white.colour.eval(s));
            for k in 0..3 {
                let got = l0[i * N + i][k];
                assert!(
                    (got - c[k] * a).abs() < 1e-4,
                    "s={s}: colour {got} vs {}",
                    c[k] * a
                );
            }
        }
    });
}

#[test]
fn constant_functions_give_closed_forms() {
    with_context(|ctx| {
        let (alpha, m) = (0.35f32, [0.8f32, 0.5, 0.25]);
        let tf = tf(&format!(
            "colour = [[0.0, 0.5, 1.0, 0.25]]\nopacity = [[0.0, {alpha}]]\nmedium = [[0.0, {}, {}, {}]]\n",
            m[0], m[1], m[2]
        ));
        let (l0, l1) = gpu_table(ctx, &tf);
        // Closed form of eq. 4.16 for constant σ = -ln(1-α), medium m, colour c over one
        // reference step: C = c σ (1 - (1-α) m) / (σ - ln m).
        let sigma = -(1.0 - alpha as f64).ln();
        for (f, b) in [(0, 0), (0, 255), (255, 0), (17, 200), (128, 128)] {
            let g0 = l0[b * N + f];
            let g1 = l1[b * N + f];
            assert!((g0[3] - alpha).abs() < 1e-5, "alpha {}", g0[3]);
            for k in 0..3 {
                assert!((g1[k] - m[k]).abs() < 1e-5, "medium {} vs {}", g1[k], m[k]);
                let c = [0.5, 1.0, 0.25][k];
                let expected = c * sigma * (1.0 - (1.0 - alpha as f64) * m[k] as f64)
                    / (sigma - (m[k] as f64).ln());
                assert!(
                    (g0[k] as f64 - expected).abs() < 1e-4,
                    "colour {} vs {expected}",
                    g0[k]
                );
            }
        }
    });
}

#[test]
fn tinted_slab_filters_the_background_by_m_to_the_thickness() {
    with_context(|ctx| {
        let m = [0.9f32, 0.7, 0.95];
        let tf = tf(&format!("medium = [[0.0, {}, {}, {}]]\n", m[0], m[1], m[2]));
        let slab = procedural::slab([16, 16, 8], 1.0).unwrap();
        for preintegrated in [false, true] {
            for sd in [1.0f32, 0.37] {
                let opts = RenderOptions {
                    width: 32,
                    height: 32,
                    sample_distance: sd,
                    preintegrated,
                    background: [1.0, 1.0, 1.0, 1.0],
                    ..Default::default()
                };
                let frame = render(ctx, &slab, &tf, &face_on(3.0, 10.0), &opts);
                let p = frame.pixel(16, 16);
                for k in 0..3 {
                    let expected = m[k].powf(8.0);
                    assert!(
                        (p[k] - expected).abs() <= 1.0 / 255.0,
                        "channel {k} (sd {sd}, preint {preintegrated}): {} vs m^8 = {expected}",
                        p[k]
                    );
                }
            }
        }
    });
}

/// A ball whose value falls linearly with radius, and a TF whose opacity is a thin spike:
/// the iso-shell at the spike is thinner than the coarse step, which makes point sampling
/// alias (thesis Fig. 3.5) while preintegration integrates it exactly along each segment.
#[test]
fn preintegration_removes_thin_spike_artefacts() {
    with_context(|ctx| {
        let n = 48u32;
        let mut vox = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = [x, y, z].map(|i| (i as f32 + 0.5) / n as f32 - 0.5);
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    vox.push((1.0 - r / 0.5).clamp(0.0, 1.0));
                }
            }
        }
        let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(vox)).unwrap();
        vol.range = Some((0.0, 1.0));
        let tf = tf(r#"
colour = [[0.0, 1.0, 0.8, 0.6]]
opacity = [[0.0, 0.0], [0.49, 0.0], [0.5, 0.9], [0.51, 0.0], [1.0, 0.0]]
"#);
        let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
        let cam = refrakt::render::Camera {
            azimuth: 20.0,
            elevation: 10.0,
            distance: 2.0,
            fov_y: 40.0,
            ..Default::default()
        };
        let base = RenderOptions {
            width: 64,
            height: 64,
            background: [0.0; 4],
            ..Default::default()
        };
        let reference = r
            .render(
                Model::Ea,
                &cam,
                &RenderOptions {
                    sample_distance: 0.05,
                    preintegrated: false,
                    ..base.clone()
                },
            )
            .unwrap();
        let mut coarse = |pre: bool| {
            r.render(
                Model::Ea,
                &cam,
                &RenderOptions {
                    sample_distance: 2.5,
                    preintegrated: pre,
                    ..base.clone()
                },
            )
            .unwrap()
        };
        let (plain, pre) = (coarse(false), coarse(true));
        let err = |f: &refrakt::render::Frame| -> f64 {
            f.pixels
                .iter()
                .zip(&reference.pixels)
                .map(|(a, b)| (0..4).map(|i| (a[i] - b[i]).abs() as f64).sum::<f64>())
                .sum::<f64>()
                / f.pixels.len() as f64
        };
        let (e_plain, e_pre) = (err(&plain), err(&pre));
        println!("mean abs error vs fine reference: point-sampled {e_plain:.4}, preintegrated {e_pre:.4}");
        assert!(
            e_pre < 0.5 * e_plain,
            "preintegrated {e_pre} not clearly better than {e_plain}"
        );
    });
}

#[test]
fn table_is_rebuilt_only_when_the_transfer_functions_change() {
    with_context(|ctx| {
        let vol = procedural::sphere(16, 0.3, 1.0).unwrap();
        let tf = TransferFunctions::load("sphere-white").unwrap();
        let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
        let opts = RenderOptions {
            width: 16,
            height: 16,
            ..Default::default()
        };
        let cam = Default::default();
        let f1 = r.render(Model::Ea, &cam, &opts).unwrap();
        assert_eq!(r.preintegration().builds(), 1);
        assert!(f1.timings.get("preintegration").is_some());
        let f2 = r.render(Model::Ea, &cam, &opts).unwrap();
        assert_eq!(r.preintegration().builds(), 1, "rebuilt without a change");
        assert!(f2.timings.get("preintegration").is_none());
        r.set_transfer_functions(&tf.clone()).unwrap();
        r.render(Model::Ea, &cam, &opts).unwrap();
        assert_eq!(
            r.preintegration().builds(),
            1,
            "an identical TF triggered a rebuild"
        );
        let mut changed = tf.clone();
        changed.opacity = refrakt::transfer::Piecewise::constant([0.3]);
        r.set_transfer_functions(&changed).unwrap();
        let f3 = r.render(Model::Ea, &cam, &opts).unwrap();
        assert_eq!(
            r.preintegration().builds(),
            2,
            "a changed TF did not rebuild"
        );
        assert_ne!(f1.pixels, f3.pixels, "the new TF did not reach the image");
    });
}

#[test]
fn bad_transfer_function_files_name_the_file_and_entry() {
    let cases = [
        ("opacity = [[0.5, 0.1], [0.2, 0.3]]", "opacity[1]", "sorted"),
        ("opacity = [[1.5, 0.1]]", "opacity[0]", "outside [0, 1]"),
        ("colour = [[0.0, nan, 0.0, 0.0]]", "colour[0]", "finite"),
        ("opacity = [[0.0, -0.1]]", "opacity[0]", "must be in [0, 1]"),
        (
            "eta = [[0.0, 1.0], [1.0, 0.0]]",
            "eta[1]",
            "between 0.25 and 4",
        ),
        ("eta = [[0.0, -2.0]]", "eta[0]", "between 0.25 and 4"),
        (
            "eta = [[0.0, 1.0], [1.0, 1e9]]",
            "eta[1]",
            "between 0.25 and 4",
        ),
        ("", "", "defines no transfer function"),
        ("name = \"only a name\"", "", "defines no transfer function"),
        ("medium = [[0.0, 1.0, 1.0]]", "medium[0]", "4 numbers"),
        ("opacty = [[0.0, 0.1]]", "opacty", "unknown field"),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (i, (text, entry, why)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&path, text).unwrap();
        let err = format!(
            "{:#}",
            TransferFunctions::load(path.to_str().unwrap()).unwrap_err()
        );
        assert!(
            err.contains(path.to_str().unwrap()),
            "no file name in: {err}"
        );
        assert!(
            err.contains(entry) && err.contains(why),
            "'{text}': expected {entry} / {why} in: {err}"
        );
        // The CLI fails with the same message and a non-zero exit, without a panic.
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_refrakt"))
            .args(["render", "--tf", path.to_str().unwrap(), "-o", "x.png"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(entry) && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
    let err = format!(
        "{:#}",
        TransferFunctions::load("/no/such/tf.toml").unwrap_err()
    );
    assert!(
        err.contains("/no/such/tf.toml") && err.contains("no such file"),
        "{err}"
    );
}

#[test]
fn presets_render() {
    with_context(|ctx| {
        let vol = procedural::shell(24, 1).unwrap();
        // The volume's values as the transfer functions see them (in [0, 1]).
        let values: Vec<f32> = match &vol.voxels {
            Voxels::U8(v) => v.iter().map(|&x| x as f32 / 255.0).collect(),
            Voxels::U16(v) => v.iter().map(|&x| x as f32 / 65535.0).collect(),
            Voxels::F32(v) => {
                let (lo, hi) = vol.range.unwrap_or((0.0, 1.0));
                v.iter().map(|&x| (x - lo) / (hi - lo)).collect()
            }
        };
        let lo = values.iter().cloned().fold(f32::MAX, f32::min);
        let hi = values.iter().cloned().fold(f32::MIN, f32::max);
        let opts = RenderOptions {
            width: 16,
            height: 16,
            ..Default::default()
        };
        let empty = TransferFunctions {
            opacity: refrakt::transfer::Piecewise::new(vec![(0.0, [0.0])]),
            ..TransferFunctions::load("supernova").unwrap()
        };
        let background = render(ctx, &vol, &empty, &Default::default(), &opts);
        for (name, _) in refrakt::transfer::PRESETS {
            let tf = TransferFunctions::load(name).unwrap();
            let f = render(ctx, &vol, &tf, &Default::default(), &opts);
            assert!(
                f.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())),
                "{name}"
            );
            // Visible matter where the preset gives the shell's values opacity or a medium
            // colour, nothing where it gives neither (over the whole range trilinear
            // interpolation reaches, densely: a narrow peak between two voxel values shows).
            let range = (0..=1000).map(|i| lo + (hi - lo) * i as f32 / 1000.0);
            let opaque = range
                .clone()
                .map(|s| tf.opacity.eval(s)[0])
                .fold(0.0f32, f32::max);
            let filtered = range
                .map(|s| tf.medium.eval(s).into_iter().fold(1.0f32, f32::min))
                .fold(1.0f32, f32::min);
            let diff = f
                .pixels
                .iter()
                .zip(&background.pixels)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                .fold(0.0f32, f32::max);
            if opaque > 0.05 || filtered < 0.95 {
                assert!(
                    diff > 1e-3,
                    "{name}: opacity up to {opaque}, medium down to {filtered}, yet nothing shows"
                );
            } else if opaque == 0.0 && filtered == 1.0 {
                assert!(
                    diff < 1e-6,
                    "{name}: no matter, yet the image differs by {diff}"
                );
            }
        }
    });
}

/// Layer 2: the extremes of η over the values between front and back (largest, the middle
/// of where it is attained, smallest, the same), which the sweep uses to find films of
/// glass a value ramp crosses (tests/image_quality.rs). Checked against a dense CPU scan of
/// the η function (10 000 values per interval, and each side of every control point) on
/// transfer functions with a band (the demo's glass-floor), a band and a dip (wine glass:
/// a glass band, then an η-1 gap before the wine) and sharp steps.
#[test]
fn eta_extremes_match_a_dense_scan() {
    with_context(|ctx| {
        let step = tf(r#"
eta = [[0.0, 1.0], [0.3, 1.0], [0.3, 1.6], [0.5, 1.6], [0.5, 1.2], [1.0, 1.2]]
"#);
        for (name, tf) in [
            (
                "glass-floor",
                TransferFunctions::load("glass-floor").unwrap(),
            ),
            ("wine-glass", TransferFunctions::load("wine-glass").unwrap()),
            ("steps", step),
        ] {
            let vol = procedural::slab([4, 4, 4], 0.0).unwrap();
            let mut r = Renderer::new(ctx, &vol, &tf).unwrap();
            r.update_preintegration().unwrap();
            let table = r.preintegration().read_eta_extremes(ctx).unwrap();
            let points: Vec<f32> = tf.eta.points.iter().map(|p| p.0).collect();
            let mut worst = (0.0f64, 0.0f64);
            for b in (0..N).step_by(7).chain([N - 1]) {
                for f in (0..N).step_by(5).chain([N - 1]) {
                    let (lo, hi) = {
                        let (x, y) = (f as f32 / 255.0, b as f32 / 255.0);
                        (x.min(y), x.max(y))
                    };
                    let mut s_all: Vec<f32> = (0..=10_000)
                        .map(|k| lo + (hi - lo) * k as f32 / 10_000.0)
                        .collect();
                    for &p in &points {
                        s_all.extend(
                            [p - 1e-6, p, p + 1e-6]
                                .iter()
                                .filter(|s| (lo..=hi).contains(*s)),
                        );
                    }
                    let eta: Vec<(f32, f32)> =
                        s_all.iter().map(|&s| (s, tf.eta.eval(s)[0])).collect();
                    let g = table[b * N + f];
                    for (sign, got_eta, got_s) in [(1.0f32, g[0], g[1]), (-1.0, g[2], g[3])] {
                        let best = eta.iter().map(|e| sign * e.1).fold(f32::MIN, f32::max);
                        let at: Vec<f32> = eta
                            .iter()
                            .filter(|e| sign * e.1 >= best - 1e-5)
                            .map(|e| e.0)
                            .collect();
                        let first = at.iter().copied().fold(f32::MAX, f32::min);
                        let last = at.iter().copied().fold(f32::MIN, f32::max);
                        let want_s = 0.5 * (first + last);
                        let de = (got_eta - sign * best).abs() as f64;
                        let ds = (got_s - want_s).abs() as f64;
                        worst = (worst.0.max(de), worst.1.max(ds));
                        assert!(
                            de <= 1e-4 && ds <= 2e-3,
                            "{name}: [{lo}, {hi}] sign {sign}: table ({got_eta}, {got_s}), \
                             scan ({}, {want_s})",
                            sign * best
                        );
                    }
                }
            }
            println!("{name}: worst |Δη| {:.1e}, |Δs| {:.1e}", worst.0, worst.1);
        }
    });
}

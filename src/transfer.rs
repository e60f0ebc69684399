//! Transfer functions of the thesis' optical model (sect. 4.1): particle colour c_tf,
//! opacity α_tf, medium colour m_tf and refractive index η_tf, each a piecewise-linear
//! function of the normalised scalar value s ∈ [0,1].
//!
//! Opacity is specified for a reference sample distance of one voxel (sample distance 1.0,
//! the smallest voxel side); renderers correct it for their actual step (eq. 3.13).
//! With η ≡ 1 and m ≡ white the model is plain emission–absorption volume rendering.
//!
//! On the GPU the four functions are sampled at [`TF_SAMPLES`] points into one 1D image with
//! two layers of RGBA32F: layer 0 = (colour.rgb, opacity), layer 1 = (medium.rgb, η).

use std::path::Path;

use anyhow::{anyhow, bail, ensure, Context as _, Result};
use serde::Deserialize;

/// Samples per transfer function on the GPU (defined with the shaders' other limits).
pub use crate::render::limits::TF_SAMPLES;

/// The range of refractive indices a transfer function may give (relative to the medium
/// around the volume, 1): beyond it the sweep's Snell steps and the preintegration table
/// leave the physics they were built for (a 1e9 rendered a white image with values up
/// to 1.7e6).
pub const MIN_ETA: f64 = 0.25;
pub const MAX_ETA: f64 = 4.0;

/// Control points allowed per function (the preintegration shader reads them from a
/// fixed-size buffer).
pub const MAX_POINTS_PER_FUNCTION: usize = 256;

/// One piecewise-linear function: control points `(s, value)` with non-decreasing s in
/// [0,1]. Two points at the same s make a step. Outside the first/last point the value is
/// held constant.
#[derive(Clone, Debug, PartialEq)]
pub struct Piecewise<const N: usize> {
    pub points: Vec<(f32, [f32; N])>,
}

impl<const N: usize> Piecewise<N> {
    pub fn constant(v: [f32; N]) -> Self {
        Self {
            points: vec![(0.0, v)],
        }
    }

    pub fn new(points: Vec<(f32, [f32; N])>) -> Self {
        Self { points }
    }

    /// Value at `s`, right-continuous at steps.
    pub fn eval(&self, s: f32) -> [f32; N] {
        let p = &self.points;
        if s < p[0].0 {
            return p[0].1;
        }
        // Last point with position <= s.
        let i = p.partition_point(|(x, _)| *x <= s);
        if i >= p.len() {
            return p[p.len() - 1].1;
        }
        let (x0, v0) = p[i - 1];
        let (x1, v1) = p[i];
        let t = if x1 > x0 { (s - x0) / (x1 - x0) } else { 1.0 };
        std::array::from_fn(|k| v0[k] + (v1[k] - v0[k]) * t)
    }
}

/// The four transfer functions.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunctions {
    pub name: String,
    pub colour: Piecewise<3>,
    pub opacity: Piecewise<1>,
    pub medium: Piecewise<3>,
    pub eta: Piecewise<1>,
}

impl Default for TransferFunctions {
    /// Opacity 0, colour white, medium white, η 1: renders nothing.
    fn default() -> Self {
        Self {
            name: "default".into(),
            colour: Piecewise::constant([1.0; 3]),
            opacity: Piecewise::constant([0.0]),
            medium: Piecewise::constant([1.0; 3]),
            eta: Piecewise::constant([1.0]),
        }
    }
}

/// The file format (TOML). See README "Transfer-function files".
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TfFile {
    name: Option<String>,
    description: Option<String>,
    colour: Option<Vec<Vec<f64>>>,
    opacity: Option<Vec<Vec<f64>>>,
    medium: Option<Vec<Vec<f64>>>,
    eta: Option<Vec<Vec<f64>>>,
}

/// Presets shipped in assets/tf/, embedded so the binary needs no files at run time.
pub const PRESETS: &[(&str, &str)] = &[
    ("ct-bone", include_str!("../assets/tf/ct-bone.toml")),
    ("glass", include_str!("../assets/tf/glass.toml")),
    ("wine-glass", include_str!("../assets/tf/wine-glass.toml")),
    ("supernova", include_str!("../assets/tf/supernova.toml")),
    (
        "sphere-white",
        include_str!("../assets/tf/sphere-white.toml"),
    ),
    ("glass-floor", include_str!("../assets/tf/glass-floor.toml")),
    ("piggy-bank", include_str!("../assets/tf/piggy-bank.toml")),
    ("glass-scene", include_str!("../assets/tf/glass-scene.toml")),
    ("hand", include_str!("../assets/tf/hand.toml")),
    ("head", include_str!("../assets/tf/head.toml")),
    ("water", include_str!("../assets/tf/water.toml")),
    ("ship", include_str!("../assets/tf/ship.toml")),
    ("kiwi", include_str!("../assets/tf/kiwi.toml")),
    ("lung-ct", include_str!("../assets/tf/lung-ct.toml")),
    ("mri-head", include_str!("../assets/tf/mri-head.toml")),
];

/// Refractive index the derived transfer functions give a volume's material (between
/// water's 1.33 and soft glass's 1.5: clearly refractive, still bright through).
pub const DERIVED_ETA: f32 = 1.2;

/// Where [`TransferFunctions::for_histogram`] put its boundaries (normalised values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DerivedThresholds {
    /// Background below, material above (Otsu over the whole histogram).
    pub material: f32,
    /// Transmissive medium below, opaque dense structure above (Otsu over the material).
    pub dense: f32,
}

impl TransferFunctions {
    /// Transfer functions for data nobody has chosen any for, derived from its histogram
    /// so that the renderer's point shows: the background (below Otsu's threshold) is
    /// empty; the material above it is a faintly absorbing, amber-tinted medium of
    /// refractive index [`DERIVED_ETA`] (reached over a wide ramp, so noise in the data
    /// does not become per-ray noise in the image); the densest class (Otsu's threshold
    /// within the material) is opaque and casts shadows and caustics.
    pub fn for_histogram(h: &crate::volume::histogram::Histogram) -> (Self, DerivedThresholds) {
        use crate::volume::histogram::BINS;
        let bin = |b: usize| b as f32 / BINS as f32;
        let t_bin = h.otsu(0..BINS);
        let t = bin(t_bin);
        let d = if t_bin + 2 < BINS {
            bin(h.otsu(t_bin..BINS)).max(t + 0.02)
        } else {
            (t + 0.02).min(1.0)
        };
        // Ramps: a fifth of the gap between the thresholds, at least 1/64 of the range.
        let w = ((d - t) / 5.0).max(1.0 / 64.0);
        let s = |x: f32| x.clamp(0.0, 1.0);
        let tf = Self {
            name: "derived from the data's histogram".into(),
            colour: Piecewise::new(vec![
                (0.0, [1.0, 0.8, 0.7]),
                (s(t), [1.0, 0.8, 0.7]),
                (s(d), [0.98, 0.95, 0.88]),
                (1.0, [0.98, 0.95, 0.88]),
            ]),
            opacity: Piecewise::new(vec![
                (0.0, [0.0]),
                (s(t - w), [0.0]),
                (s(t), [0.004]),
                (s(d - w), [0.004]),
                (s(d), [0.6]),
                (1.0, [0.85]),
            ]),
            medium: Piecewise::new(vec![
                (0.0, [1.0; 3]),
                (s(t - w), [1.0; 3]),
                (s(t), [0.997, 0.99, 0.97]),
                (1.0, [0.997, 0.99, 0.97]),
            ]),
            eta: Piecewise::new(vec![
                (0.0, [1.0]),
                (s(t - 2.0 * w), [1.0]),
                (s(t + 2.0 * w), [DERIVED_ETA]),
                (1.0, [DERIVED_ETA]),
            ]),
        };
        (
            tf,
            DerivedThresholds {
                material: t,
                dense: d,
            },
        )
    }

    /// The largest opacity over the normalised values `lo..=hi` (the piecewise-linear
    /// function's maximum: at the ends or at a control point between them).
    pub fn max_opacity(&self, lo: f32, hi: f32) -> f32 {
        let ends = [self.opacity.eval(lo)[0], self.opacity.eval(hi)[0]];
        self.opacity
            .points
            .iter()
            .filter(|(x, _)| (lo..=hi).contains(x))
            .map(|(_, v)| v[0])
            .chain(ends)
            .fold(0.0, f32::max)
    }

    /// Where the opacity is above 0: the first and last normalised value (sampled at
    /// 1/1024), `None` if nowhere.
    pub fn opaque_range(&self) -> Option<(f32, f32)> {
        let xs: Vec<f32> = (0..=1024)
            .map(|i| i as f32 / 1024.0)
            .filter(|&x| self.opacity.eval(x)[0] > 0.0)
            .collect();
        Some((*xs.first()?, *xs.last()?))
    }
}

/// The presets with their one-line descriptions (the files' `description`), for
/// `--list-presets`.
pub fn preset_descriptions() -> Vec<(&'static str, String)> {
    PRESETS
        .iter()
        .map(|(name, text)| {
            let d = toml::from_str::<TfFile>(text)
                .ok()
                .and_then(|f| f.description)
                .unwrap_or_default();
            (*name, d)
        })
        .collect()
}

impl TransferFunctions {
    /// A preset name (see [`PRESETS`]) or a path to a TOML file.
    pub fn load(name_or_path: &str) -> Result<Self> {
        if let Some((name, text)) = PRESETS.iter().find(|(n, _)| *n == name_or_path) {
            return Self::parse(text, &format!("preset '{name}'"));
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            let names: Vec<&str> = PRESETS.iter().map(|(n, _)| *n).collect();
            bail!(
                "transfer function '{name_or_path}': no such file, and not a preset ({})",
                names.join(", ")
            );
        }
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading transfer function file {}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parse TOML text; `origin` names the file in every error.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let file: TfFile =
            toml::from_str(text).map_err(|e| anyhow!("{origin}: {}", e.to_string().trim_end()))?;
        let _ = file.description;
        let has_function = file.colour.is_some()
            || file.opacity.is_some()
            || file.medium.is_some()
            || file.eta.is_some();
        let mut tf = TransferFunctions {
            name: file.name.unwrap_or_else(|| origin.to_string()),
            ..Default::default()
        };
        if let Some(p) = file.colour {
            tf.colour = parse_points::<3>(&p, origin, "colour", |v| v >= 0.0, "must be >= 0")?;
        }
        if let Some(p) = file.opacity {
            tf.opacity = parse_points::<1>(
                &p,
                origin,
                "opacity",
                |v| (0.0..=1.0).contains(&v),
                "must be in [0, 1]",
            )?;
        }
        if let Some(p) = file.medium {
            tf.medium = parse_points::<3>(
                &p,
                origin,
                "medium",
                |v| (0.0..=1.0).contains(&v),
                "must be in [0, 1] (a filter transmits at most all light)",
            )?;
        }
        if let Some(p) = file.eta {
            tf.eta = parse_points::<1>(
                &p,
                origin,
                "eta",
                |v| (MIN_ETA..=MAX_ETA).contains(&v),
                "must be between 0.25 and 4 (a relative refractive index; water 1.33, glass \
                 1.5, diamond 2.42)",
            )?;
        }
        ensure!(
            has_function,
            "{origin}: defines no transfer function (give at least one of colour, opacity, \
             medium, eta)"
        );
        Ok(tf)
    }

    /// Serialise to the TOML file format (round-trips through [`Self::parse`]).
    pub fn to_toml(&self) -> String {
        fn rows<const N: usize>(key: &str, p: &Piecewise<N>) -> String {
            let items: Vec<String> = p
                .points
                .iter()
                .map(|(s, v)| {
                    let vals: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
                    format!("  [{s:?}, {}],", vals.join(", "))
                })
                .collect();
            format!("{key} = [\n{}\n]\n", items.join("\n"))
        }
        format!(
            "name = {:?}\n{}{}{}{}",
            self.name,
            rows("colour", &self.colour),
            rows("opacity", &self.opacity),
            rows("medium", &self.medium),
            rows("eta", &self.eta)
        )
    }

    /// Whether η has an interior extremum: rises and then falls (or falls and then rises)
    /// along the values. Only then can a ramp between two values pass through a band of η
    /// past both its ends (a film, which the sweep treats as one face between them);
    /// a monotone η makes none.
    pub fn eta_has_films(&self) -> bool {
        let (mut rose, mut fell) = (false, false);
        for w in self.eta.points.windows(2) {
            let d = w[1].1[0] - w[0].1[0];
            rose |= d > 0.0;
            fell |= d < 0.0;
        }
        rose && fell
    }

    /// The texels of the 1D TF image: layer 0 then layer 1, each `TF_SAMPLES` RGBA f32,
    /// sample i at s = i / (TF_SAMPLES - 1).
    pub fn texels(&self) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
        let n = TF_SAMPLES as usize;
        let mut l0 = Vec::with_capacity(n);
        let mut l1 = Vec::with_capacity(n);
        for i in 0..n {
            let s = i as f32 / (n - 1) as f32;
            let c = self.colour.eval(s);
            let a = self.opacity.eval(s)[0];
            let m = self.medium.eval(s);
            let e = self.eta.eval(s)[0];
            l0.push([c[0], c[1], c[2], a]);
            l1.push([m[0], m[1], m[2], e]);
        }
        (l0, l1)
    }

    /// The control points as the preintegration shader reads them (std430): a header of
    /// `count` (uvec4) and `offset` (uvec4) for colour, opacity, medium, eta, then every
    /// point as (s, value.xyz) (scalar functions use x only).
    pub fn control_points(&self) -> Vec<[f32; 4]> {
        fn push<const N: usize>(out: &mut Vec<[f32; 4]>, p: &Piecewise<N>) {
            for (s, v) in &p.points {
                let mut row = [*s, 0.0, 0.0, 0.0];
                row[1..1 + N].copy_from_slice(v);
                out.push(row);
            }
        }
        let counts = [
            self.colour.points.len(),
            self.opacity.points.len(),
            self.medium.points.len(),
            self.eta.points.len(),
        ];
        let mut offsets = [0usize; 4];
        for i in 1..4 {
            offsets[i] = offsets[i - 1] + counts[i - 1];
        }
        let mut out = vec![
            counts.map(|c| f32::from_bits(c as u32)),
            offsets.map(|o| f32::from_bits(o as u32)),
        ];
        push(&mut out, &self.colour);
        push(&mut out, &self.opacity);
        push(&mut out, &self.medium);
        push(&mut out, &self.eta);
        out
    }

    /// Total number of control points over the four functions.
    pub fn point_count(&self) -> usize {
        self.colour.points.len()
            + self.opacity.points.len()
            + self.medium.points.len()
            + self.eta.points.len()
    }
}

fn parse_points<const N: usize>(
    rows: &[Vec<f64>],
    origin: &str,
    key: &str,
    valid: impl Fn(f64) -> bool,
    rule: &str,
) -> Result<Piecewise<N>> {
    if rows.is_empty() {
        bail!("{origin}: {key}: needs at least one control point");
    }
    if rows.len() > MAX_POINTS_PER_FUNCTION {
        bail!(
            "{origin}: {key}: {} control points, at most {MAX_POINTS_PER_FUNCTION} are supported",
            rows.len()
        );
    }
    let mut points = Vec::with_capacity(rows.len());
    let mut prev_s = f64::NEG_INFINITY;
    for (i, row) in rows.iter().enumerate() {
        let at = format!("{origin}: {key}[{i}]");
        if row.len() != N + 1 {
            bail!(
                "{at}: expected [s, {}] ({} numbers), got {} numbers",
                if N == 1 { "value" } else { "r, g, b" },
                N + 1,
                row.len()
            );
        }
        // Finite as f32 too: 3.5e38 would become infinity on the GPU.
        if let Some(bad) = row.iter().find(|x| !(**x as f32).is_finite()) {
            if bad.is_finite() {
                bail!("{at}: {bad} is beyond the range of 32-bit floats (±3.4e38)");
            }
            bail!("{at}: {bad} is not a finite number");
        }
        let s = row[0];
        if !(0.0..=1.0).contains(&s) {
            bail!("{at}: position s = {s} is outside [0, 1]");
        }
        if s < prev_s {
            bail!("{at}: control points must be sorted by s, but s = {s} comes after {prev_s}");
        }
        if i >= 2 && s == prev_s && rows[i - 2][0] == s {
            bail!("{at}: more than two control points at s = {s} (two make a step)");
        }
        for &v in &row[1..] {
            if !valid(v) {
                bail!("{at}: value {v} {rule}");
            }
        }
        prev_s = s;
        points.push((s as f32, std::array::from_fn(|k| row[k + 1] as f32)));
    }
    Ok(Piecewise { points })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three classes (air 10, tissue 100, bone 220 of 255): the derived functions leave
    /// air empty with η 1, make tissue a faint medium of η [`DERIVED_ETA`] and bone opaque.
    #[test]
    fn derived_transfer_functions_follow_the_histograms_classes() {
        use crate::volume::{histogram::Histogram, Volume, Voxels};
        let mut v = vec![10u8; 6000];
        v.extend(vec![100u8; 3000]);
        v.extend(vec![220u8; 1000]);
        let vol = Volume::new([2500, 2, 2], [1.0; 3], Voxels::U8(v)).unwrap();
        let (tf, t) = TransferFunctions::for_histogram(&Histogram::of(&vol));
        let at = |x: u8| x as f32 / 255.0;
        assert!(at(10) < t.material && t.material <= at(100), "{t:?}");
        assert!(at(100) < t.dense && t.dense <= at(220), "{t:?}");
        assert_eq!(
            (tf.opacity.eval(at(10))[0], tf.eta.eval(at(10))[0]),
            (0.0, 1.0)
        );
        let tissue = tf.opacity.eval(at(100))[0];
        assert!(tissue > 0.0 && tissue < 0.01, "tissue opacity {tissue}");
        assert_eq!(tf.eta.eval(at(100))[0], DERIVED_ETA);
        assert!(tf.opacity.eval(at(220))[0] >= 0.6);
        assert!(
            tf.medium.eval(at(100)).iter().all(|&m| m < 1.0),
            "tinted medium"
        );
        // The empty-image check sees it: opacity over the data's range.
        assert!(tf.max_opacity(at(10), at(220)) >= 0.6);
        assert_eq!(tf.max_opacity(0.0, at(10)), 0.0);
    }

    #[test]
    fn eval_interpolates_and_steps() {
        let p = Piecewise::<1>::new(vec![(0.2, [0.0]), (0.4, [1.0]), (0.4, [0.5]), (1.0, [0.5])]);
        assert_eq!(p.eval(0.0), [0.0]);
        assert!((p.eval(0.3)[0] - 0.5).abs() < 1e-6);
        assert_eq!(p.eval(0.4), [0.5]);
        assert_eq!(p.eval(0.9), [0.5]);
    }

    #[test]
    fn presets_parse_and_round_trip() {
        for (name, _) in PRESETS {
            let tf = TransferFunctions::load(name).unwrap();
            let again = TransferFunctions::parse(&tf.to_toml(), "round trip").unwrap();
            assert_eq!(tf, again, "{name}");
        }
    }

    /// Films need η to rise and fall (or fall and rise) along the values: the presets
    /// with a band of η (glass under a floor or wine, the hand's bone band, the
    /// supernova's shell band) have them; a ramp to a plateau (CT, MRI, the ship's block),
    /// a constant or a step up have none.
    #[test]
    fn films_need_an_interior_extremum_of_eta() {
        for (name, films) in [
            ("glass-floor", true),
            ("wine-glass", true),
            ("hand", true),
            ("supernova", true),
            ("lung-ct", false),
            ("head", false),
            ("ship", false),
            ("glass", false),
        ] {
            let tf = TransferFunctions::load(name).unwrap();
            assert_eq!(tf.eta_has_films(), films, "{name}");
        }
        let mut tf = TransferFunctions::default();
        assert!(!tf.eta_has_films(), "constant eta");
        tf.eta = Piecewise::new(vec![(0.0, [1.0]), (0.5, [1.0]), (0.5, [1.5]), (1.0, [1.5])]);
        assert!(!tf.eta_has_films(), "a step up");
        tf.eta = Piecewise::new(vec![(0.0, [1.5]), (0.5, [1.0]), (1.0, [1.2])]);
        assert!(tf.eta_has_films(), "a dip");
    }
}

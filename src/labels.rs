//! Label volumes (segmentations): integer voxels whose values name categories, not
//! quantities. Such a volume gets a categorical transfer function, each label its own
//! colour, opacity and η, and is classified by its nearest voxel
//! ([`crate::volume::Volume::labels`]: the renderer samples it without interpolation and
//! without preintegration), so two labels side by side never blend into the values
//! between them, which may be other labels or none.
//!
//! Colours come from a colour table, in 3D Slicer's format (`index name R G B A`, 0–255,
//! `#` comments; an optional seventh column is our η) or ITK-SNAP's label description
//! (`IDX R G B A VIS MSH "LABEL"`, A in 0–1), or from a built-in palette.

use std::path::Path;

use anyhow::{bail, ensure, Context as _, Result};

use crate::transfer::{Piecewise, TransferFunctions};
use crate::volume::{Volume, Voxels};

/// A volume with at most this many distinct integer values is taken as a label map when
/// its transfer functions are derived from the data (`--labels auto`).
pub const MAX_AUTO_LABELS: usize = 64;

/// The most labels a volume may have: the preintegration table tells `PREINT_SIZE` (256)
/// values apart per axis, and a label volume reaches the GPU as each voxel's label index
/// ([`index_voxels`]), label k at k / 255.
pub const MAX_LABELS: usize = crate::render::limits::PREINT_SIZE as usize;

/// Opacity per reference sample of a label whose table alpha is 1: translucent enough to
/// see one label through another.
pub const LABEL_OPACITY: f32 = 0.5;

/// One label's look.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    pub value: f64,
    pub name: String,
    pub colour: [f32; 3],
    /// Table alpha, 0–1 (0: not drawn).
    pub alpha: f32,
    pub eta: f32,
}

/// The distinct values of an integer-valued volume, sorted, or `None` when there are more
/// than `max` or a value is not an integer (a continuous scan).
pub fn distinct_values(volume: &Volume, max: usize) -> Option<Vec<f64>> {
    let mut seen: Vec<f64> = Vec::new();
    let mut add = |v: f64| -> bool {
        if let Err(at) = seen.binary_search_by(|x| x.total_cmp(&v)) {
            if seen.len() >= max {
                return false;
            }
            seen.insert(at, v);
        }
        true
    };
    match &volume.voxels {
        Voxels::U8(v) => {
            let mut hist = [false; 256];
            v.iter().for_each(|&x| hist[x as usize] = true);
            for (i, _) in hist.iter().enumerate().filter(|(_, h)| **h) {
                if !add(i as f64) {
                    return None;
                }
            }
        }
        Voxels::U16(v) => {
            let mut hist = vec![false; 65536];
            v.iter().for_each(|&x| hist[x as usize] = true);
            for (i, _) in hist.iter().enumerate().filter(|(_, h)| **h) {
                if !add(i as f64) {
                    return None;
                }
            }
        }
        Voxels::F32(v) => {
            let mut last = f32::NAN;
            for &x in v {
                if x == last {
                    continue;
                }
                if x.fract() != 0.0 || !add(x as f64) {
                    return None;
                }
                last = x;
            }
        }
    }
    Some(seen)
}

/// A distinct colour for label `k` of the built-in palette (k ≥ 1; 0 is the background).
fn palette(k: usize) -> [f32; 3] {
    // Twelve well-separated hues, then the same at lower saturation.
    const HUES: [[u8; 3]; 12] = [
        [230, 25, 75],
        [60, 180, 75],
        [255, 225, 25],
        [0, 130, 200],
        [245, 130, 48],
        [145, 30, 180],
        [70, 240, 240],
        [240, 50, 230],
        [210, 245, 60],
        [250, 190, 212],
        [0, 128, 128],
        [170, 110, 40],
    ];
    let c = HUES[(k - 1) % HUES.len()];
    let mix = if ((k - 1) / HUES.len()) % 2 == 1 {
        0.5
    } else {
        0.0
    };
    c.map(|x| (x as f32 / 255.0) * (1.0 - mix) + mix)
}

/// Labels for `values` from the built-in palette: the value 0 is the background (not
/// drawn), the others get the palette's colours in order.
pub fn default_labels(values: &[f64]) -> Vec<Label> {
    let mut k = 0;
    values
        .iter()
        .map(|&v| {
            let background = v == 0.0;
            if !background {
                k += 1;
            }
            Label {
                value: v,
                name: if background {
                    "background".into()
                } else {
                    format!("label {v}")
                },
                colour: if background { [0.0; 3] } else { palette(k) },
                alpha: if background { 0.0 } else { 1.0 },
                eta: 1.0,
            }
        })
        .collect()
}

/// Reads a colour table (3D Slicer or ITK-SNAP; module docs).
pub fn read_table(path: &Path) -> Result<Vec<Label>> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    ensure!(
        bytes.len() <= 16 << 20,
        "{}: {} bytes is too large for a colour table",
        path.display(),
        bytes.len()
    );
    let text = String::from_utf8_lossy(&bytes);
    parse_table(&text).with_context(|| format!("colour table {}", path.display()))
}

/// [`read_table`] on text.
pub fn parse_table(text: &str) -> Result<Vec<Label>> {
    let mut labels = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let line_no = n + 1;
        // ITK-SNAP: the name is quoted at the end; Slicer: the name is the second word.
        let (fields, name) = match line.find('"') {
            Some(q) => (
                line[..q].split_whitespace().collect::<Vec<_>>(),
                line[q..].trim_matches('"').to_string(),
            ),
            None => {
                let mut f: Vec<&str> = line.split_whitespace().collect();
                ensure!(
                    f.len() >= 6,
                    "line {line_no}: '{line}': expected 'index name R G B A' (3D Slicer) or \
                     'IDX R G B A VIS MSH \"LABEL\"' (ITK-SNAP)"
                );
                let name = f.remove(1).to_string();
                (f, name)
            }
        };
        let num = |i: usize, what: &str| -> Result<f64> {
            let s = fields
                .get(i)
                .with_context(|| format!("line {line_no}: no {what}"))?;
            let v: f64 = s
                .parse()
                .with_context(|| format!("line {line_no}: {what} '{s}' is not a number"))?;
            ensure!(v.is_finite(), "line {line_no}: {what} '{s}' is not finite");
            Ok(v)
        };
        let value = num(0, "index")?;
        let rgb = [num(1, "R")?, num(2, "G")?, num(3, "B")?];
        for c in rgb {
            ensure!(
                (0.0..=255.0).contains(&c),
                "line {line_no}: colour {c} is outside 0–255"
            );
        }
        let itk = line.contains('"');
        let a = num(4, "A")?;
        let alpha = if itk { a } else { a / 255.0 };
        ensure!(
            (0.0..=1.0).contains(&alpha),
            "line {line_no}: alpha {a} is outside {}",
            if itk { "0–1" } else { "0–255" }
        );
        // ITK-SNAP: VIS 0 hides the label.
        let visible = !itk || fields.get(5).map_or(true, |v| *v != "0");
        let eta = if itk {
            1.0
        } else {
            match fields.get(5) {
                Some(_) => num(5, "η")?,
                None => 1.0,
            }
        };
        ensure!(
            (1.0..=3.0).contains(&eta),
            "line {line_no}: η {eta} is outside 1–3"
        );
        // Two colours for one label: which is meant?
        ensure!(
            !labels.iter().any(|l: &Label| l.value == value),
            "line {line_no}: label {value} is given twice"
        );
        labels.push(Label {
            value,
            name,
            colour: rgb.map(|c| (c / 255.0) as f32),
            alpha: if visible { alpha as f32 } else { 0.0 },
            eta: eta as f32,
        });
    }
    if labels.is_empty() {
        bail!("no labels (lines 'index name R G B A')");
    }
    Ok(labels)
}

/// Replaces each voxel by the index of its value in `values` (the volume's distinct values,
/// sorted, at most [`MAX_LABELS`]) as 8-bit voxels, so that label k is k / 255 on the GPU:
/// its own entry of the preintegration table and of the sampled transfer functions,
/// whatever the values' type and spread (16-bit labels 0, 2 and 4 were 0, 3e-5 and 6e-5
/// of the 16-bit range: one entry, one colour). Use [`indexed_table`] and
/// [`categorical`] over the indices with the range (0, 255) with it.
pub fn index_voxels(volume: &mut Volume, values: &[f64]) -> Result<()> {
    ensure!(
        values.len() <= MAX_LABELS,
        "{} labels: at most {MAX_LABELS} can be told apart",
        values.len()
    );
    let index = |v: f64| -> Result<u8> {
        values
            .binary_search_by(|x| x.total_cmp(&v))
            .map(|k| k as u8)
            .map_err(|_| anyhow::anyhow!("value {v} is not one of the volume's labels"))
    };
    let indices = match &volume.voxels {
        Voxels::U8(v) => {
            let mut lut = [0u8; 256];
            for (i, l) in lut.iter_mut().enumerate() {
                *l = index(i as f64).unwrap_or(0);
            }
            v.iter().map(|&x| lut[x as usize]).collect()
        }
        Voxels::U16(v) => {
            let mut lut = vec![0u8; 65536];
            for &value in values {
                lut[value as usize] = index(value)?;
            }
            v.iter().map(|&x| lut[x as usize]).collect()
        }
        Voxels::F32(v) => v
            .iter()
            .map(|&x| index(x as f64))
            .collect::<Result<Vec<u8>>>()?,
    };
    volume.voxels = Voxels::U8(indices);
    volume.range = None;
    Ok(())
}

/// `table` for a volume whose voxels [`index_voxels`] replaced: each label of `values`
/// renumbered to its index (labels the volume lacks left out).
pub fn indexed_table(table: &[Label], values: &[f64]) -> Vec<Label> {
    table
        .iter()
        .filter_map(|l| {
            let k = values.binary_search_by(|x| x.total_cmp(&l.value)).ok()?;
            Some(Label {
                value: k as f64,
                ..l.clone()
            })
        })
        .collect()
}

/// The categorical transfer functions: label k's colour, opacity and η over the values
/// nearer to it than to any other label; between two labels the functions step halfway.
/// Values `range` (raw, the volume's lo..hi) map to 0..1 as the upload maps them. Labels
/// the table does not list and values the table lists but the volume lacks are
/// transparent / unused.
pub fn categorical(labels: &[Label], present: &[f64], range: (f32, f32)) -> TransferFunctions {
    let (lo, hi) = (range.0 as f64, range.1 as f64);
    let s = |v: f64| (((v - lo) / (hi - lo).max(f64::MIN_POSITIVE)) as f32).clamp(0.0, 1.0);
    let look = |v: f64| labels.iter().find(|l| l.value == v);
    let mut colour = Vec::new();
    let mut opacity = Vec::new();
    let mut eta = Vec::new();
    for (k, &v) in present.iter().enumerate() {
        let start = if k == 0 {
            0.0
        } else {
            s((present[k - 1] + v) / 2.0)
        };
        let end = match present.get(k + 1) {
            Some(&next) => s((v + next) / 2.0),
            None => 1.0,
        };
        let (c, a, e) = match look(v) {
            Some(l) => (l.colour, l.alpha * LABEL_OPACITY, l.eta),
            None => ([0.0; 3], 0.0, 1.0),
        };
        // Two points per label: a step at each boundary (two points at one s).
        colour.extend([(start, c), (end, c)]);
        opacity.extend([(start, [a]), (end, [a])]);
        eta.extend([(start, [e]), (end, [e])]);
    }
    TransferFunctions {
        name: format!("categorical, {} labels", present.len()),
        colour: Piecewise::new(colour),
        opacity: Piecewise::new(opacity),
        medium: Piecewise::constant([1.0; 3]),
        eta: Piecewise::new(eta),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_given_twice_is_refused() {
        let e = parse_table("1 a 255 0 0 255\n1 dup 0 255 0 255\n").unwrap_err();
        assert!(
            e.to_string().contains("line 2: label 1 is given twice"),
            "{e}"
        );
    }

    #[test]
    fn tables_of_both_formats() {
        let slicer = "# Color table\n0 Background 0 0 0 0\n1 liver 220 100 90 255\n\
                      2 bone 241 214 145 128 1.5\n";
        let l = parse_table(slicer).unwrap();
        assert_eq!(l.len(), 3);
        assert_eq!(l[1].name, "liver");
        assert_eq!(l[1].colour, [220.0 / 255.0, 100.0 / 255.0, 90.0 / 255.0]);
        assert_eq!((l[2].alpha, l[2].eta), (128.0 / 255.0, 1.5));
        let itk = "################\n    0     0    0    0        0  0  0    \"Clear Label\"\n\
                   1   255    0    0        1  1  1    \"Label 1\"\n\
                   2     0  255    0        1  0  1    \"hidden\"\n";
        let l = parse_table(itk).unwrap();
        assert_eq!(l[1].name, "Label 1");
        assert_eq!((l[1].colour, l[1].alpha), ([1.0, 0.0, 0.0], 1.0));
        assert_eq!(l[2].alpha, 0.0, "VIS 0 hides the label");
        for bad in [
            "",
            "1 a 300 0 0 255",
            "1 a 1 2 3",
            "x a 1 2 3 4",
            "1 a 1 2 3 4 0.5",
        ] {
            assert!(parse_table(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn distinct_values_tell_labels_from_scans() {
        let labels = Volume::new(
            [4, 4, 4],
            [1.0; 3],
            Voxels::U8((0..64).map(|i| (i % 3) as u8 * 7).collect()),
        )
        .unwrap();
        assert_eq!(distinct_values(&labels, 64), Some(vec![0.0, 7.0, 14.0]));
        let scan = Volume::new(
            [4, 4, 4],
            [1.0; 3],
            Voxels::U8((0..64).map(|i| i as u8).collect()),
        )
        .unwrap();
        assert_eq!(distinct_values(&scan, 32), None);
        let float = Volume::new(
            [4, 4, 4],
            [1.0; 3],
            Voxels::F32((0..64).map(|i| (i % 2) as f32 + 0.5).collect()),
        )
        .unwrap();
        assert_eq!(
            distinct_values(&float, 64),
            None,
            "non-integer values are no labels"
        );
    }
}

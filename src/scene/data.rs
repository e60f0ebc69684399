//! What loading a volume file decides that the user should see: its spacing, value range
//! and window, transfer functions derived from its histogram when none were chosen, and a
//! warning when its values fall where the transfer functions are transparent.

use super::{Scene, VolumeSource};
use crate::transfer::TransferFunctions;
use crate::volume::Volume;

impl Scene {
    /// For volumes read from files: the transfer functions derived from the histogram
    /// when the scene asks for that, notes on what was used, and a warning when the data
    /// falls where the opacity is 0 (the image would be empty).
    pub(super) fn check_data(
        &self,
        volume: &Volume,
        tf: Option<TransferFunctions>,
    ) -> (TransferFunctions, Vec<String>) {
        let from_file = matches!(
            self.volume,
            VolumeSource::File { .. } | VolumeSource::Fetched { .. }
        );
        let mut notes = Vec::new();
        if let (false, Some(tf)) = (from_file, &tf) {
            // Built-in data with its own preset: nothing to report or derive.
            return (tf.clone(), notes);
        }
        let h = crate::volume::histogram::Histogram::of(volume);
        // The raw values behind normalised ones (one pass over f32 data, not one a value).
        let (lo, hi) = volume.value_range();
        let raw = |s: f32| lo + s * (hi - lo);
        if from_file {
            // One range: the data's values, and what maps to 0 .. 1 only where a window
            // makes that another range.
            let window = match &self.volume {
                VolumeSource::File {
                    window: Some(w), ..
                }
                | VolumeSource::Fetched {
                    window: Some(w), ..
                } => format!("; window {} .. {} → 0 .. 1", short(w.0), short(w.1)),
                _ => " → 0 .. 1 (no --window)".into(),
            };
            // The data's own extremes: with a window, the histogram sees values clamped
            // to it, so f32 data (what windowed data become) are scanned once more.
            let (data_lo, data_hi) = match (&volume.voxels, volume.range) {
                (crate::volume::Voxels::F32(v), Some(_)) => v
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    }),
                _ => (raw(h.min), raw(h.max)),
            };
            let [sx, sy, sz] = volume.spacing;
            notes.push(format!(
                "volume {}x{}x{} {}, spacing {} × {} × {}, values {} .. {}{window}",
                volume.dims[0],
                volume.dims[1],
                volume.dims[2],
                volume.stored.unwrap_or(volume.voxels.type_name()),
                short(sx),
                short(sy),
                short(sz),
                short(data_lo),
                short(data_hi),
            ));
        }
        let tf = match tf {
            Some(tf) => tf,
            None => {
                let (tf, t) = TransferFunctions::for_histogram(&h);
                notes.push(format!(
                    "transfer functions derived from the histogram: background below {} \
                     (normalised {:.3}), refractive medium (eta {}) above it, opaque above \
                     {} ({:.3}); choose others with --tf",
                    short(raw(t.material)),
                    t.material,
                    crate::transfer::DERIVED_ETA,
                    short(raw(t.dense)),
                    t.dense
                ));
                tf
            }
        };
        if from_file && h.min == h.max {
            // One value everywhere: no window can separate anything (the hint below would
            // suggest --window V,V, which is refused).
            log::warn!(
                "{}: every voxel holds the same value ({}): there is nothing to tell apart, \
                 and the image will be empty or a uniform block",
                self.name,
                short(raw(h.min)),
            );
        } else if from_file && tf.max_opacity(h.min, h.max) <= 0.0 {
            let opaque = match tf.opaque_range() {
                Some((a, b)) => format!("only for normalised values {a:.3} .. {b:.3}"),
                None => "nowhere".into(),
            };
            log::warn!(
                "{}: the data's values ({} .. {}, normalised {:.3} .. {:.3}) all fall where \
                 the transfer functions '{}' have opacity 0 (opacity > 0 {opaque}): the image \
                 will be empty; map the data onto them with --window LO,HI (e.g. --window \
                 {},{}) or choose other transfer functions with --tf",
                self.name,
                short(raw(h.min)),
                short(raw(h.max)),
                h.min,
                h.max,
                tf.name,
                short(raw(h.min)),
                short(raw(h.max)),
            );
        }
        (tf, notes)
    }
}

/// A data value for messages: integers as such, others to a sensible precision.
fn short(x: f32) -> String {
    if x.fract() == 0.0 || x.abs() >= 100.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.3}")
    }
}

//! Dispersion (issue 35 item 3): the refractive index per colour channel, from one Abbe
//! number for all refractive matter.
//!
//! The transfer function's η is the index at the Fraunhofer d line (587.6 nm, the green
//! channel). Red and blue take the indices at the C line (656.3 nm) and the F line
//! (486.1 nm), the lines the Abbe number is defined by,
//!
//!   V = (n_d − 1) / (n_F − n_C),
//!
//! with the index between them following Cauchy's two-term formula n(λ) = A + B / λ². Then
//! n_c − 1 = (n_d − 1) s_c with s_c = 1 + (λ_c⁻² − λ_d⁻²) / (V (λ_F⁻² − λ_C⁻²)): every
//! channel's η is the d line's scaled about 1, which is exactly what the refractive-index
//! scale k does (η' = 1 + k (η − 1)), so a channel's rays and wavefront run through the
//! field of scale k s_c. For V = 59 (crown glass) s = 0.9949, 1, 1.0119; for V = 20 (dense
//! flint) 0.9850, 1, 1.0350.

use anyhow::{ensure, Result};

use crate::render::model_options::ModelOption;
use crate::render::RenderOptions;

/// The Fraunhofer C, d and F lines (nm): the wavelengths the red, green and blue channels
/// stand for.
pub const WAVELENGTHS_NM: [f64; 3] = [656.27, 587.56, 486.13];

/// The smallest and largest Abbe numbers taken (optical glasses lie within about 17–95;
/// below 5 the red channel's index would fall towards 1 and Cauchy's formula means
/// little).
pub const MIN_ABBE: f64 = 5.0;
pub const MAX_ABBE: f64 = 1000.0;

/// `--abbe` (scene key `abbe`): dispersion, off at 0.
pub static ABBE: ModelOption = ModelOption {
    flag: "--abbe",
    value_name: "V",
    help: "Dispersion: the Abbe number V = (n_d - 1) / (n_F - n_C) of all refractive matter, \
           5-1000, or 0 for none. The transfer function's eta is the index at 587.6 nm (green); \
           red and blue take the indices at 656.3 and 486.1 nm (Cauchy's formula). Crown glass \
           about 59, dense flint about 20, water about 56. The light is simulated once per \
           colour channel and viewing rays that meet refractive matter are traced once per \
           channel (about three times the time)",
    default: 0.0,
    integer: false,
    check: |v| {
        ensure!(
            v == 0.0 || (MIN_ABBE..=MAX_ABBE).contains(&v),
            "the Abbe number must be 0 (no dispersion) or from {MIN_ABBE} to {MAX_ABBE}"
        );
        Ok(())
    },
};

/// The factor s_c per channel (red, green, blue) on the d line's η − 1 for Abbe number
/// `abbe` (module docs).
pub fn channel_factors(abbe: f64) -> [f64; 3] {
    let inv_sq = |nm: f64| 1.0 / (nm * 1e-3 * nm * 1e-3);
    let [c, d, f] = WAVELENGTHS_NM.map(inv_sq);
    [c, d, f].map(|l| 1.0 + (l - d) / (abbe * (f - c)))
}

/// The refractive-index scale each colour channel runs with, where `opts` asks for
/// dispersion (`--abbe`); `None` without. Refused where a channel's scale would pass the
/// largest scale the renderer takes.
pub fn channel_eta_scales(opts: &RenderOptions) -> Result<Option<[f32; 3]>> {
    let abbe = opts.model_option(&ABBE);
    if abbe == 0.0 {
        return Ok(None);
    }
    let k = opts.sweep.eta_scale as f64;
    let scales = channel_factors(abbe).map(|s| (k * s) as f32);
    let max = crate::render::MAX_ETA_SCALE;
    ensure!(
        scales[2] <= max,
        "with the Abbe number {abbe}, blue's refractive-index scale would be {:.3}, past the \
         largest the renderer takes ({max}): lower the --eta-scale {k}",
        scales[2]
    );
    Ok(Some(scales))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factors reproduce the Abbe number's definition with a Cauchy index between the
    /// lines: (n_d − 1) / (n_F − n_C) = V, and n(λ) = A + B / λ² through all three.
    #[test]
    fn factors_keep_the_abbe_number_and_cauchy_s_form() {
        for (n_d, v) in [(1.5168f64, 64.17f64), (1.7552, 27.58), (1.333, 55.8)] {
            let n = channel_factors(v).map(|s| 1.0 + (n_d - 1.0) * s);
            assert!((n[1] - n_d).abs() < 1e-12);
            let abbe = (n[1] - 1.0) / (n[2] - n[0]);
            assert!((abbe - v).abs() < 1e-9 * v, "V {abbe} for {v}");
            // Cauchy: (n - A) λ² = B for the three lines, A from the outer two.
            let l2 = WAVELENGTHS_NM.map(|l| l * l);
            let b = (n[2] - n[0]) / (1.0 / l2[2] - 1.0 / l2[0]);
            let a = n[0] - b / l2[0];
            assert!(
                (a + b / l2[1] - n[1]).abs() < 1e-12,
                "d line off Cauchy's curve"
            );
        }
        // N-BK7 (Schott: n_C 1.51432, n_d 1.51680, n_F 1.52238, V 64.17): Cauchy through
        // its C and F lines puts d within 3e-4 of the catalogue.
        let n = channel_factors(64.17).map(|s| 1.0 + 0.5168 * s);
        assert!(
            (n[0] - 1.51432).abs() < 3e-4 && (n[2] - 1.52238).abs() < 3e-4,
            "{n:?}"
        );
    }
}

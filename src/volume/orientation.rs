//! Where a volume's voxel axes point in the patient: [`Volume::axes`](super::Volume::axes)
//! holds each axis as a unit vector in DICOM's LPS frame (+x towards the patient's left,
//! +y posterior, +z superior). Files state it in several ways; this module turns each
//! into that form.
//!
//! Two conventions for three-letter codes exist and both are common:
//! - **"to"** (DICOM, NIfTI tools such as nibabel, NRRD's `space`, and `--orientation`):
//!   each letter names the side the axis points towards; "RAS" is +x right, +y anterior,
//!   +z superior, and "LPS" is the DICOM patient frame.
//! - **"from"** (ITK's `SpatialOrientation`, and so MetaImage's `AnatomicalOrientation`):
//!   each letter names the side the axis comes from; ITK's "RAI" is the "to" code LPS.

use anyhow::{bail, Result};

/// The unit LPS vector of an anatomical direction letter (the side it points towards).
fn towards(letter: char) -> Option<[f32; 3]> {
    Some(match letter.to_ascii_uppercase() {
        'L' => [1.0, 0.0, 0.0],
        'R' => [-1.0, 0.0, 0.0],
        'P' => [0.0, 1.0, 0.0],
        'A' => [0.0, -1.0, 0.0],
        'S' => [0.0, 0.0, 1.0],
        'I' => [0.0, 0.0, -1.0],
        _ => return None,
    })
}

/// The voxel axes of a three-letter code in the "to" convention (module docs): "RAS",
/// "LPS", "PIR", ... One letter from each pair L/R, A/P, S/I, in any order.
pub fn parse_code(code: &str) -> Result<[[f32; 3]; 3]> {
    let letters: Vec<char> = code.trim().chars().collect();
    let explain = "three letters, one from each of L/R, A/P and S/I, naming the side \
                   each voxel axis x, y, z points towards (e.g. RAS, LPS, LAS)";
    if letters.len() != 3 {
        bail!("orientation '{code}': {explain}");
    }
    let mut axes = [[0.0f32; 3]; 3];
    for (k, &c) in letters.iter().enumerate() {
        let Some(v) = towards(c) else {
            bail!("orientation '{code}': '{c}' is not one of L, R, A, P, S, I ({explain})");
        };
        axes[k] = v;
    }
    // Each anatomical axis once: the three vectors are then a signed permutation.
    for j in 0..3 {
        if axes.iter().filter(|a| a[j] != 0.0).count() != 1 {
            let pair = ["L/R", "A/P", "S/I"][j];
            bail!("orientation '{code}': needs exactly one letter of {pair} ({explain})");
        }
    }
    Ok(axes)
}

/// The voxel axes of a code in ITK's "from" convention (MetaImage's
/// `AnatomicalOrientation`): each axis points away from the side its letter names.
pub(crate) fn parse_itk_code(code: &str) -> Result<[[f32; 3]; 3]> {
    Ok(parse_code(code)?.map(|a| a.map(|x| -x)))
}

/// Three direction vectors (any length) as unit vectors; `None` if one is zero, not
/// finite, or the three are not independent (a degenerate matrix states no orientation).
pub(crate) fn unit_axes(dirs: [[f64; 3]; 3]) -> Option<[[f32; 3]; 3]> {
    let mut out = [[0.0f32; 3]; 3];
    for (k, d) in dirs.iter().enumerate() {
        let l = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(l.is_finite() && l > 0.0) {
            return None;
        }
        out[k] = d.map(|x| (x / l) as f32);
    }
    let [a, b, c] = out.map(glam::Vec3::from);
    (a.cross(b).dot(c).abs() > 1e-3).then_some(out)
}

/// A direction in the renderer's world frame (x right, y up, z towards the default
/// camera) as the LPS vector [`Volume::turn_upright`](super::Volume::turn_upright) maps
/// back to it: world x = L, y = S, z = A. For formats whose world has no anatomy (VTK):
/// their directions then place the voxel axes in our world as they were in theirs.
pub(crate) fn world_to_lps(d: [f32; 3]) -> [f32; 3] {
    [d[0], -d[2], d[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_in_both_conventions() {
        assert_eq!(
            parse_code("LPS").unwrap(),
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        );
        assert_eq!(
            parse_code("ras").unwrap(),
            [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
        );
        // Permuted axes: x towards the patient's front, y towards the feet, z right.
        assert_eq!(
            parse_code("AIR").unwrap(),
            [[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]
        );
        // ITK's RAI is LPS.
        assert_eq!(parse_itk_code("RAI").unwrap(), parse_code("LPS").unwrap());
        for bad in ["", "RA", "RASX", "RLS", "RAA", "XYZ", "R A"] {
            assert!(parse_code(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn degenerate_direction_matrices_state_nothing() {
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(unit_axes(id).is_some());
        assert!(unit_axes([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        assert!(unit_axes([[0.0; 3], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        assert!(unit_axes([[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        // Scaled vectors are normalised.
        let s = unit_axes([[2.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 3.0]]).unwrap();
        assert_eq!(s, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    }
}

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

use anyhow::{bail, ensure, Result};

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

/// A turn of the volume in quarter turns about the world's axes: a signed permutation
/// matrix, new world coordinates = `R` × old (row k: the old axis new axis k takes, with
/// its sign).
pub type QuarterTurns = [[i8; 3]; 3];

/// Parse `--rotate`: turns about the world's axes (x right, y up, z towards the camera),
/// applied in the order given, each an axis letter and a multiple of 90 degrees,
/// right-handed (x90 turns +y to +z): "x90", "y-90,z180". Other angles are refused: the
/// volume's box stays aligned with the world's axes, so only quarter turns keep every
/// voxel (the camera turns the view by any angle).
pub fn parse_rotation(spec: &str) -> Result<QuarterTurns> {
    let mut r: QuarterTurns = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
    let spec = spec.trim();
    ensure!(
        !spec.is_empty(),
        "expected turns such as \"x90\" or \"y-90,z180\" (an axis x, y or z and degrees)"
    );
    for part in spec.split(',') {
        let part = part.trim();
        let mut chars = part.chars();
        let axis = match chars.next().map(|c| c.to_ascii_lowercase()) {
            Some('x') => 0,
            Some('y') => 1,
            Some('z') => 2,
            _ => {
                bail!("'{part}': a turn starts with its axis x, y or z, then degrees, e.g. \"x90\"")
            }
        };
        let degrees = chars.as_str().trim_start_matches(':').trim();
        let degrees: i64 = degrees.parse().map_err(|_| {
            anyhow::anyhow!("'{part}': '{degrees}' is not a whole number of degrees")
        })?;
        ensure!(
            degrees % 90 == 0,
            "'{part}': only quarter turns (multiples of 90 degrees) can turn the volume, \
             whose box stays aligned with the world's axes; turn the camera for other angles"
        );
        let quarters = (degrees / 90).rem_euclid(4);
        for _ in 0..quarters {
            r = mul(quarter_turn(axis), r);
        }
    }
    Ok(r)
}

/// A right-handed quarter turn about world axis `axis` (x90: y → z, z → −y).
fn quarter_turn(axis: usize) -> QuarterTurns {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut m = [[0i8; 3]; 3];
    m[axis][axis] = 1;
    // new_b = old_a, new_a = −old_b.
    m[b][a] = 1;
    m[a][b] = -1;
    m
}

fn mul(a: QuarterTurns, b: QuarterTurns) -> QuarterTurns {
    let mut m = [[0i8; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turns_are_right_handed_and_compose_in_order() {
        // x90 turns +y (up) to +z (towards the camera) and +z to −y.
        assert_eq!(
            parse_rotation("x90").unwrap(),
            [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
        );
        // y90 turns +z to +x; z90 turns +x to +y.
        assert_eq!(
            parse_rotation("y90").unwrap(),
            [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]
        );
        assert_eq!(
            parse_rotation("z90").unwrap(),
            [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
        );
        // Four quarter turns, or −90 then 90, are no turn; 270 is −90.
        let id = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
        assert_eq!(parse_rotation("x360").unwrap(), id);
        assert_eq!(parse_rotation("z-90, z90").unwrap(), id);
        assert_eq!(
            parse_rotation("y270").unwrap(),
            parse_rotation("y-90").unwrap()
        );
        // In order: x90 then z90 takes +y to +z (x90), which z90 leaves; taken the other
        // way round, +y goes to −x (z90), which x90 leaves.
        let xz = parse_rotation("x90,z90").unwrap();
        let zx = parse_rotation("z90,x90").unwrap();
        let image = |r: [[i8; 3]; 3], v: [i8; 3]| -> [i8; 3] {
            [0, 1, 2].map(|i| (0..3).map(|j| r[i][j] * v[j]).sum())
        };
        assert_eq!(image(xz, [0, 1, 0]), [0, 0, 1]);
        assert_eq!(image(zx, [0, 1, 0]), [-1, 0, 0]);
        for (bad, needle) in [
            ("x45", "quarter turns"),
            ("w90", "axis x, y or z"),
            ("x", "whole number"),
            ("", "expected turns"),
        ] {
            let e = parse_rotation(bad).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }

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

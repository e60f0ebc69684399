//! Issue 36, "volume files upright and to scale": the orientation a MetaImage
//! (`TransformMatrix`), a VTK image (`Direction`) or a NIfTI (sform) states, or the one
//! `--orientation` gives a raw file, turns the volume so the patient stands upright facing
//! the camera; and a file that states no spacing is warned about.
//!
//! One marker, a bright 4³ block in a 16³ volume at voxel corner (high x, low y, low z).
//! Every file below says that x points superior, y towards the patient's right and z
//! posterior ("SRP" in the DICOM/NIfTI convention). So the marker lies superior, to the
//! patient's left and anterior: seen from the front (the camera on +z, the patient facing
//! it), in the upper right of the image. Read as plain voxel axes (x right, y up) it would
//! sit in the lower right: that is where a file without an orientation puts it.

mod common;
#[path = "common/samples.rs"]
mod samples;

use std::path::{Path, PathBuf};

use common::refrakt;
use samples::nifti_header;

const N: usize = 16;

fn marker() -> Vec<u8> {
    let mut v = vec![0u8; N * N * N];
    for z in 0..4 {
        for y in 0..4 {
            for x in N - 4..N {
                v[x + N * (y + N * z)] = 255;
            }
        }
    }
    v
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn mha(extra: &str) -> Vec<u8> {
    let header = format!(
        "ObjectType = Image\nNDims = 3\n{extra}ElementSpacing = 1 1 1\nDimSize = {N} {N} \
         {N}\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
    );
    [header.into_bytes(), marker()].concat()
}

fn vti(direction: &str) -> Vec<u8> {
    let ascii: Vec<String> = marker().iter().map(|v| v.to_string()).collect();
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" \
         byte_order=\"LittleEndian\">\n<ImageData WholeExtent=\"0 {m} 0 {m} 0 {m}\" \
         Origin=\"0 0 0\" Spacing=\"1 1 1\"{direction}>\n<Piece Extent=\"0 {m} 0 {m} 0 {m}\">\n\
         <PointData Scalars=\"v\">\n<DataArray type=\"UInt8\" Name=\"v\" format=\"ascii\">\n\
         {}\n</DataArray>\n</PointData>\n</Piece>\n</ImageData>\n</VTKFile>\n",
        ascii.join(" "),
        m = N - 1
    )
    .into_bytes()
}

/// A NIfTI whose sform (RAS, scaled by the spacing) has columns `cols` (voxel axes).
fn nifti(cols: [[f32; 3]; 3]) -> Vec<u8> {
    let mut h = nifti_header(
        &[N as i16, N as i16, N as i16],
        2,
        8,
        [1.0; 3],
        352.0,
        0.0,
        0.0,
        false,
    );
    h[254..256].copy_from_slice(&1i16.to_le_bytes()); // sform_code: scanner
    for (r, row) in [280usize, 296, 312].iter().enumerate() {
        for (c, col) in cols.iter().enumerate() {
            h[row + 4 * c..row + 4 * c + 4].copy_from_slice(&col[r].to_le_bytes());
        }
    }
    [h, marker()].concat()
}

/// Renders `file` from the front (EA, unlit) and returns the brightness-weighted centroid
/// of the image, in [-1, 1] with +x right and +y up, and the pixels; and stderr.
fn centroid(file: &Path, extra: &[&str], out: &Path) -> ([f64; 2], Vec<[f32; 3]>, String) {
    let mut args = vec![
        "render",
        file.to_str().unwrap(),
        "--model",
        "ea",
        "--width",
        "32",
        "--height",
        "32",
        "--azimuth",
        "0",
        "--elevation",
        "0",
        "--background",
        "0,0,0,1",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let o = refrakt(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {err}");
    let (w, px) = common::read_exr_rgb(out);
    let h = px.len() / w;
    let (mut sx, mut sy, mut sum) = (0.0, 0.0, 0.0);
    for (i, p) in px.iter().enumerate() {
        let l = (p[0] + p[1] + p[2]) as f64;
        let (x, y) = (i % w, i / w);
        sx += l * ((x as f64 + 0.5) / w as f64 * 2.0 - 1.0);
        sy += l * (1.0 - (y as f64 + 0.5) / h as f64 * 2.0);
        sum += l;
    }
    assert!(sum > 0.0, "{}: an empty image", file.display());
    ([sx / sum, sy / sum], px, err)
}

fn quadrant(c: [f64; 2]) -> &'static str {
    match (c[0] > 0.15, c[0] < -0.15, c[1] > 0.15, c[1] < -0.15) {
        (true, _, true, _) => "upper right",
        (true, _, _, true) => "lower right",
        (_, true, true, _) => "upper left",
        (_, true, _, true) => "lower left",
        _ => "centre",
    }
}

#[test]
fn stated_orientations_put_the_marker_where_the_anatomy_says() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("o.exr");
    // x → S, y → R, z → P. MetaImage: ITK's LPS frame, row i = voxel axis i.
    let mha_oriented = write(d, "m.mha", &mha("TransformMatrix = 0 0 1 -1 0 0 0 1 0\n"));
    // The same in ITK's "from" code: x from I, y from L, z from A.
    let mha_code = write(d, "c.mha", &mha("AnatomicalOrientation = ILA\n"));
    let mha_plain = write(d, "p.mha", &mha(""));
    // NIfTI: RAS columns. S = (0,0,1), R = (1,0,0), P = (0,-1,0).
    let nii = write(
        d,
        "n.nii",
        &nifti([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]),
    );
    // VTK: no anatomy; its world is ours (x right, y up, z towards the viewer). Direction
    // row by row, column k = voxel axis k: x → up, y → left, z → away from the viewer,
    // where the anatomical files put S, R and P: the same image.
    let vti_oriented = write(d, "v.vti", &vti(" Direction=\"0 -1 0 1 0 0 0 0 -1\""));
    let vti_identity = write(d, "i.vti", &vti(" Direction=\"1 0 0 0 1 0 0 0 1\""));
    let raw = write(d, "mk_16x16x16_uint8.raw", &marker());

    let (reference, ref_px, _) = centroid(&mha_oriented, &[], &out);
    assert_eq!(
        quadrant(reference),
        "upper right",
        "MetaImage TransformMatrix: {reference:?}"
    );
    for (file, extra, want) in [
        (&mha_code, &[][..], "upper right"),
        (&nii, &[][..], "upper right"),
        (&vti_oriented, &[][..], "upper right"),
        (&raw, &["--orientation", "SRP"][..], "upper right"),
        (&mha_plain, &[][..], "lower right"),
        (&vti_identity, &[][..], "lower right"),
        (&raw, &[][..], "lower right"),
        // --orientation replaces what the file says; --upright off keeps the voxel axes.
        (&mha_oriented, &["--orientation", "RAS"][..], "lower left"),
        (&mha_oriented, &["--upright", "off"][..], "lower right"),
    ] {
        let (c, px, _) = centroid(file, extra, &out);
        assert_eq!(
            quadrant(c),
            want,
            "{} {extra:?}: centroid {c:?}",
            file.display()
        );
        if want == "upper right" {
            // The same volume turned the same way: the same image.
            let diff = px
                .iter()
                .zip(&ref_px)
                .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0f32, f32::max))
                .fold(0.0f32, f32::max);
            assert!(
                diff < 1e-5,
                "{} {extra:?}: differs by {diff}",
                file.display()
            );
        }
    }
}

#[test]
fn quarter_turns_move_the_marker_as_the_right_hand_rule_says() {
    // The raw marker, read as plain voxel axes, sits at +x, −y, −z: lower right from the
    // front. Each turn is right-handed about a world axis (x right, y up, z towards the
    // camera) and turns are applied in the order given.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("o.exr");
    let raw = write(d, "mk_16x16x16_uint8.raw", &marker());
    let mut turned = Vec::new();
    for (turns, want) in [
        // z90: +x → +y, +y → −x.
        ("z90", "upper right"),
        ("z180", "upper left"),
        // x90: +y → +z, −z → +y: the marker comes up, now in front.
        ("x90", "upper right"),
        // y90: +z → +x, +x → −z: the marker, at the back, goes left.
        ("y90", "lower left"),
        // In order: x90 brings it up (+x, +y), then z90 takes +x to +y and +y to −x.
        ("x90,z90", "upper left"),
        ("z90,x90", "upper right"),
    ] {
        let (c, px, _) = centroid(&raw, &["--rotate", turns], &out);
        assert_eq!(quadrant(c), want, "--rotate {turns}: centroid {c:?}");
        if turns == "z180" {
            turned = px;
        }
    }
    // Half a turn about z is the mirror in x and in y, voxel for voxel.
    let (_, flipped, _) = centroid(&raw, &["--flip", "xy"], &out);
    assert_eq!(turned, flipped, "--rotate z180 and --flip xy differ");
    let o = refrakt(&[
        "render",
        raw.to_str().unwrap(),
        "--rotate",
        "x45",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("--rotate") && err.contains("quarter turns"),
        "{err}"
    );
}

#[test]
fn unstated_spacing_is_warned_about_and_a_sidecar_states_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("o.exr");
    let raw = write(d, "mk_16x16x16_uint8.raw", &marker());
    let (_, _, err) = centroid(&raw, &[], &out);
    assert!(
        err.contains("does not state its voxel spacing") && err.contains("--spacing"),
        "no warning for a raw file without spacing: {err}"
    );
    let (_, _, err) = centroid(&raw, &["--spacing", "1,1,2"], &out);
    assert!(
        !err.contains("voxel spacing"),
        "warned despite --spacing: {err}"
    );
    // A sidecar named as the open-scivis collection names its descriptions.
    write(
        d,
        "mk.json",
        br#"{"name": "marker", "size": [16, 16, 16], "spacing": [1, 1, 4], "type": "uint8"}"#,
    );
    let o = refrakt(&[
        "render",
        raw.to_str().unwrap(),
        "--model",
        "ea",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    let (stdout, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{err}");
    assert!(
        !err.contains("voxel spacing"),
        "warned despite the sidecar: {err}"
    );
    assert!(
        stdout.contains("spacing 1 × 1 × 4"),
        "sidecar spacing not used: {stdout}"
    );
    // A sidecar describing another file is an error naming it, not silently used.
    write(
        d,
        "mk.json",
        br#"{"size": [32, 16, 16], "spacing": [1, 1, 4]}"#,
    );
    let o = refrakt(&["render", raw.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("mk.json") && err.contains("another file"),
        "{err}"
    );
}

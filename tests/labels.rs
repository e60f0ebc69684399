//! Issue 36, "label volumes in colour": a segmentation gets a categorical transfer
//! function from a colour table and is classified by its nearest voxel, so two labels
//! side by side never show the colour of a value between them.
//!
//! The volume: label 2 on the left, label 4 on the right, background 0 around. The table
//! also has label 3, green, which the volume does not contain: interpolating across the
//! 2 | 4 boundary passes through 3 and would paint a green seam there (measured: with the
//! volume sampled trilinearly the seam's pixels are green). Seen face on, unlit (EA),
//! each half must be its label's colour and nothing green anywhere.

mod common;

use common::refrakt;

const N: usize = 20;

/// `render` of the label volume `raw` with the colour table `table`, face on, unlit
/// background black, 40², into `out`.
fn render_face_on(
    raw: &std::path::Path,
    table: &std::path::Path,
    model: &str,
    out: &std::path::Path,
) -> std::process::Output {
    refrakt(&[
        "render",
        raw.to_str().unwrap(),
        "--labels",
        table.to_str().unwrap(),
        "--model",
        model,
        "--spacing",
        "1,1,1",
        "--azimuth",
        "0",
        "--elevation",
        "0",
        "--background",
        "0,0,0,1",
        "--width",
        "40",
        "--height",
        "40",
        "-o",
        out.to_str().unwrap(),
    ])
}

#[test]
fn labels_take_their_table_colours_and_never_blend() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = vec![0u8; N * N * N];
    for z in 4..N - 4 {
        for y in 4..N - 4 {
            for x in 4..N - 4 {
                v[x + N * (y + N * z)] = if x < N / 2 { 2 } else { 4 };
            }
        }
    }
    let raw = dir.path().join("seg_20x20x20_uint8.raw");
    std::fs::write(&raw, &v).unwrap();
    let table = dir.path().join("seg.ctbl");
    std::fs::write(
        &table,
        "# 3D Slicer colour table\n0 Background 0 0 0 0\n2 left 255 0 0 255\n\
         3 between 0 255 0 255\n4 right 0 0 255 255\n",
    )
    .unwrap();
    let out = dir.path().join("o.exr");
    for model in ["ea", "refract"] {
        let o = render_face_on(&raw, &table, model, &out);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            stdout.contains("label volume: 3 labels (0 .. 4)") && stdout.contains("seg.ctbl"),
            "{stdout}"
        );
        let (w, px) = common::read_exr_rgb(&out);
        let (mut red_left, mut blue_right, mut green) = (0, 0, 0.0f32);
        for (i, p) in px.iter().enumerate() {
            let x = i % w;
            let (r, g, b) = (p[0], p[1], p[2]);
            // Green beyond what light and shading could mix in: none of the labels has any.
            green = green.max(g / (r + g + b).max(1e-3));
            if r > 0.05 && r > 4.0 * b && x < w / 2 {
                red_left += 1;
            }
            if b > 0.05 && b > 4.0 * r && x >= w / 2 {
                blue_right += 1;
            }
        }
        println!("{model}: red left {red_left}, blue right {blue_right}, green share {green:.4}");
        assert!(
            red_left > 100 && blue_right > 100,
            "{model}: labels not in their colours"
        );
        assert!(
            green < 0.02,
            "{model}: a green share of {green:.3}: the labels blended"
        );
    }
}

/// A 16-bit segmentation of 201 labels: 2 (red, left) and 4 (blue, right), and 198 more in a
/// corner of the bottom slice that the table leaves out (not drawn). Two faults this
/// held: 16-bit labels were their values over 65535 on the GPU, so 0, 2 and 4 shared one
/// entry of the 256-entry preintegration table (one colour for all); and more than 170
/// labels overran the preintegration's control points (two points of three functions
/// each). More than 256 labels are refused by name.
#[test]
fn hundreds_of_sixteen_bit_labels_keep_their_table_colours() {
    let dir = tempfile::tempdir().unwrap();
    let render = |v: &[u16], table: &str| {
        let raw = dir.path().join("seg_20x20x20_uint16.raw");
        std::fs::write(&raw, bytemuck::cast_slice::<u16, u8>(v)).unwrap();
        let ctbl = dir.path().join("seg.ctbl");
        std::fs::write(&ctbl, table).unwrap();
        let out = dir.path().join("o.exr");
        (render_face_on(&raw, &ctbl, "ea", &out), out)
    };
    let mut v = vec![0u16; N * N * N];
    for z in 4..N - 4 {
        for y in 4..N - 4 {
            for x in 4..N - 4 {
                v[x + N * (y + N * z)] = if x < N / 2 { 2 } else { 4 };
            }
        }
    }
    for (i, label) in (1000..1198).enumerate() {
        v[i] = label;
    }
    let table = "0 Background 0 0 0 0\n2 left 255 0 0 255\n4 right 0 0 255 255\n";
    let (o, out) = render(&v, table);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("label volume: 201 labels (0 .. 1197)"),
        "{stdout}"
    );
    let (w, px) = common::read_exr_rgb(&out);
    let (mut red_left, mut blue_right, mut wrong) = (0, 0, 0);
    for (i, p) in px.iter().enumerate() {
        let x = i % w;
        let (r, g, b) = (p[0], p[1], p[2]);
        if r > 0.05 && r > 4.0 * b && x < w / 2 {
            red_left += 1;
        }
        if b > 0.05 && b > 4.0 * r && x >= w / 2 {
            blue_right += 1;
        }
        // Any other colour (a label drawn that the table leaves out, or a blend).
        if g > 0.02 || (x < w / 2 && b > 0.02) || (x >= w / 2 && r > 0.02) {
            wrong += 1;
        }
    }
    println!("red left {red_left}, blue right {blue_right}, other colours {wrong}");
    assert!(red_left > 100 && blue_right > 100 && wrong == 0);
    // 257 labels: refused, naming the limit.
    for (i, label) in (1000..1255).enumerate() {
        v[i] = label;
    }
    let (o, _) = render(&v, table);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("more than 256 distinct values"),
        "{stderr}"
    );
}

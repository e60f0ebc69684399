//! The command line as a user meets it: `info`, `render` to PNG and EXR, and clear errors
//! with a non-zero exit (never a panic) on bad input.

mod common;

use std::path::Path;
use std::process::Output;

use common::{refrakt, refrakt_command};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Whether lavapipe is among the devices (a test of its limits says why it skips if not).
fn on_lavapipe(why: &str) -> bool {
    let info = refrakt(&["info"]);
    let yes = String::from_utf8_lossy(&info.stdout).contains("llvmpipe");
    if !yes {
        eprintln!("skipped: {why}");
    }
    yes
}

/// Fails unless the command exited non-zero with `needle` in its error and no panic.
fn assert_clean_failure(args: &[&str], needle: &str) {
    let o = refrakt(args);
    let err = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded; stderr: {err}");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert!(
        err.contains(needle),
        "{args:?}: expected '{needle}' in: {err}"
    );
}

#[test]
fn info_lists_the_device_and_limits() {
    let o = refrakt(&["info"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    let device = std::env::var("REFRAKT_EXPECT_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    assert!(out.contains(&device), "no '{device}' in:\n{out}");
    for key in [
        "max 3D image size",
        "max array layers",
        "max push constants",
        "timestamps",
        "memory heaps",
    ] {
        assert!(out.contains(key), "no '{key}' in:\n{out}");
    }
}

#[test]
fn render_writes_png_and_exr_with_timings() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["png", "exr"] {
        let path = dir.path().join(format!("out.{ext}"));
        let p = path.to_str().unwrap();
        let o = refrakt(&[
            "render",
            "-o",
            p,
            "--width",
            "40",
            "--height",
            "30",
            "--volume-size",
            "24",
        ]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", stderr(&o));
        // Each pass on a line of its own, its name followed by its time ("sweep" is not
        // satisfied by "sweep setup").
        for pass in [
            "gradient volume",
            "environment SAT",
            "preintegration",
            "sweep setup",
            "sweep",
            "composite",
        ] {
            let timed = out.lines().any(|l| {
                l.trim_start().strip_prefix(pass).is_some_and(|rest| {
                    rest.starts_with(' ')
                        && rest.trim_start().starts_with(|c: char| c.is_ascii_digit())
                })
            });
            assert!(timed, "no timed '{pass}' line in:\n{out}");
        }
        for needle in [" planes as ", ", spacing ", " ms per plane"] {
            assert!(out.contains(needle), "no '{needle}' in:\n{out}");
        }
        assert!(out.contains(p), "output path not printed:\n{out}");
        // Piped, no progress is drawn (no spinner, no "% of the planes", no carriage
        // returns): only a terminal gets it.
        let err = stderr(&o);
        assert!(
            !err.contains('\r') && !err.contains("of the planes") && !err.contains("loading"),
            "progress drawn into a pipe:\n{err:?}"
        );
        let img = image_size(&path);
        assert_eq!(img, (40, 30), "{ext} dimensions");
    }
}

/// `--pass-timings` times the forward transport's three draws of every plane apart: the
/// three sums are nested in the sweep's scope (never more than it) and cover its draws
/// (most of it: what is left is barriers between planes).
#[test]
fn pass_timings_split_the_sweep_into_its_draws() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    let o = refrakt(&[
        "render",
        "-o",
        path.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--volume-size",
        "24",
        "--pass-timings",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    let ms = |name: &str| -> f64 {
        out.lines()
            .find_map(|l| {
                let rest = l.trim_start().strip_prefix(name)?;
                let v = rest.split_whitespace().next()?;
                rest.starts_with(' ')
                    .then(|| v.parse::<f64>().ok())
                    .flatten()
            })
            .unwrap_or_else(|| panic!("no '{name}' time in:\n{out}"))
    };
    let sweep = ms("sweep");
    let parts = ["sweep: light rays", "sweep: splat", "sweep: viewing rays"].map(ms);
    let sum: f64 = parts.iter().sum();
    assert!(parts.iter().all(|p| *p > 0.0), "{parts:?}\n{out}");
    assert!(
        sum <= sweep * 1.001,
        "parts {sum} ms > sweep {sweep} ms\n{out}"
    );
    assert!(
        sum >= 0.5 * sweep,
        "parts {sum} ms cover too little of {sweep} ms\n{out}"
    );
}

#[test]
fn ea_model_and_dumps_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ea.png");
    let o = refrakt(&[
        "render",
        "--model",
        "ea",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--volume-size",
        "16",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ea raymarch"));
    let out = dir.path().join("s.png");
    let o = refrakt(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "12",
        "--volume-size",
        "16",
        "--dump",
        "light-colour@3,view-direction@5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["light-colour-3.exr", "view-direction-5.exr"] {
        assert_eq!(image_size(&dir.path().join(name)), (16, 12), "{name}");
    }
}

/// The number after `key` in `line` (up to a space, comma or parenthesis).
fn number_after(line: &str, key: &str) -> f64 {
    let rest = &line[line
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in {line}"))
        + key.len()..];
    let end = rest.find([' ', ',', ')', ';']).unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("'{}' after '{key}': {e}", &rest[..end]))
}

#[test]
fn dumps_carry_their_plane_in_world_space() {
    use exr::meta::attribute::{AttributeValue, Text};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.png");
    let (az, el, dist) = (35.0f64, 25.0f64, 2.4f64);
    let target = [0.05f64, -0.1, 0.08];
    let o = refrakt(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "12",
        "--volume-size",
        "16",
        "--azimuth",
        "35",
        "--elevation",
        "25",
        "--distance",
        "2.4",
        "--fov",
        "30",
        "--target",
        "0.05,-0.1,0.08",
        "--dump",
        "light-colour@3,view-position@3",
    ]);
    let log = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(log.contains("(16x16x16,"), "{log}");

    // The camera, independently of the renderer: it orbits the target, and the planes
    // start at the depth of the box corner nearest to it (the box is [-0.5, 0.5]^3).
    let (a, e) = (az.to_radians(), el.to_radians());
    let towards_eye = [a.sin() * e.cos(), e.sin(), a.cos() * e.cos()];
    let eye: Vec<f64> = (0..3).map(|i| target[i] + dist * towards_eye[i]).collect();
    let forward: Vec<f64> = towards_eye.iter().map(|v| -v).collect();
    let dot = |p: &[f64], q: &[f64]| (0..3).map(|i| p[i] * q[i]).sum::<f64>();
    let near = (0..8)
        .map(|c| {
            let corner: Vec<f64> = (0..3)
                .map(|i| if c >> i & 1 == 0 { -0.5 } else { 0.5 } - eye[i])
                .collect();
            dot(&corner, &forward)
        })
        .fold(f64::INFINITY, f64::min);
    let sweep_line = log.lines().find(|l| l.starts_with("sweep:")).unwrap();
    let spacing = number_after(sweep_line, "spacing ");
    assert!((spacing - 1.0 / 16.0).abs() < 1e-6, "{sweep_line}");
    let depth = near + 3.0 * spacing;
    let offset = dot(&forward, &eye) + depth;

    let attributes = |name: &str| {
        let path = dir.path().join(name);
        let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
        meta.headers[0].own_attributes.other.clone()
    };
    let f32_attr = |attrs: &std::collections::HashMap<Text, AttributeValue>, key: &str| match attrs
        .get(&Text::from(key))
    {
        Some(AttributeValue::F32(v)) => *v as f64,
        v => panic!("{key}: {v:?}"),
    };
    let v3_attr = |attrs: &std::collections::HashMap<Text, AttributeValue>, key: &str| match attrs
        .get(&Text::from(key))
    {
        Some(AttributeValue::FloatVec3((x, y, z))) => [*x as f64, *y as f64, *z as f64],
        v => panic!("{key}: {v:?}"),
    };
    let close = |a: f64, b: f64, tol: f64, what: &str| {
        assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
    };

    let light = attributes("light-colour-3.exr");
    let line = log
        .lines()
        .find(|l| l.starts_with("dumped light-colour after plane 3 "))
        .unwrap_or_else(|| panic!("no dump line in:\n{log}"));
    let printed_depth = number_after(line, "view depth ");
    let printed_offset = number_after(line, " d=");
    let attr_depth = f32_attr(&light, "refrakt.viewDepth");
    // The header and the log agree (the log rounds to 4 decimals)...
    close(
        attr_depth,
        printed_depth,
        0.5e-4 + 1e-6,
        "header depth vs log",
    );
    close(
        f32_attr(&light, "refrakt.planeOffset"),
        printed_offset,
        0.5e-4 + 1e-6,
        "log d",
    );
    // ...and both agree with the geometry computed here.
    close(attr_depth, depth, 1e-4, "view depth");
    close(
        f32_attr(&light, "refrakt.planeOffset"),
        offset,
        1e-4,
        "plane offset",
    );
    let n = v3_attr(&light, "refrakt.planeNormal");
    let e = v3_attr(&light, "refrakt.cameraEye");
    let t = v3_attr(&light, "refrakt.cameraTarget");
    for i in 0..3 {
        close(n[i], forward[i], 1e-5, "plane normal");
        close(e[i], eye[i], 1e-5, "eye");
        close(t[i], target[i], 1e-7, "target");
    }
    close(f32_attr(&light, "refrakt.cameraFovY"), 30.0, 0.0, "fov");
    assert!(
        matches!(
            light.get(&Text::from("refrakt.plane")),
            Some(AttributeValue::I32(3))
        ),
        "{light:?}"
    );
    assert!(!light.contains_key(&Text::from("refrakt.positionsViewDepth")));

    // The view positions of plane k lie on plane k+1.
    let pos = attributes("view-position-3.exr");
    close(
        f32_attr(&pos, "refrakt.viewDepth"),
        depth,
        1e-4,
        "view-position depth",
    );
    close(
        f32_attr(&pos, "refrakt.positionsViewDepth"),
        depth + spacing,
        1e-4,
        "positions depth",
    );
    close(
        f32_attr(&pos, "refrakt.positionsPlaneOffset"),
        offset + spacing,
        1e-4,
        "positions offset",
    );
    // The buffer holds view-space points (z = view depth): check the claim against it.
    let img = exr::prelude::read_first_rgba_layer_from_file(
        dir.path().join("view-position-3.exr"),
        |res, _| vec![[0f32; 4]; res.width() * res.height()],
        |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * 16 + pos.x()] = [r, g, b, a];
        },
    )
    .unwrap();
    for p in &img.layer_data.channel_data.pixels {
        close(
            p[2] as f64,
            depth + spacing,
            1e-4,
            "view-space z of a view position",
        );
    }
}

#[test]
fn bad_sweep_options_are_clear_errors() {
    assert_clean_failure(
        &["render", "--dump", "light@3", "-o", "x.png"],
        "unknown state buffer 'light'",
    );
    assert_clean_failure(
        &["render", "--dump", "medium", "-o", "x.png"],
        "BUFFER@PLANE",
    );
    assert_clean_failure(
        &[
            "render",
            "--dump",
            "medium@99999",
            "--volume-size",
            "8",
            "-o",
            "x.png",
        ],
        "this frame has planes",
    );
    // The default camera looks from +z towards the origin: a light from -z is behind.
    assert_clean_failure(
        &[
            "render",
            "--light",
            "0,0,-1",
            "--azimuth",
            "0",
            "--elevation",
            "0",
            "-o",
            "x.png",
        ],
        "viewer's side",
    );
    assert_clean_failure(
        &["render", "--light", "0,0,0", "-o", "x.png"],
        "light direction",
    );
    assert_clean_failure(&["render", "--softness", "-1", "-o", "x.png"], "softness");
    for bad in ["0.1", "5", "NaN"] {
        assert_clean_failure(
            &["render", "--light-spacing", bad, "-o", "x.png"],
            "light ray spacing",
        );
    }
    assert_clean_failure(&["render", "--clip", "0,0,1", "-o", "x.png"], "--clip");
    assert_clean_failure(
        &["render", "--reflections", "maybe", "-o", "x.png"],
        "--reflections (on, off, environment or volume): \"maybe\" is neither on nor off",
    );
    // The sweep has no per-step sampling: the flag is refused there, not ignored.
    assert_clean_failure(
        &[
            "render",
            "--no-preintegration",
            "--volume-size",
            "16",
            "-o",
            "x.png",
        ],
        "option of the EA model",
    );
}

/// A storage buffer binding may not exceed the device's maxStorageBufferRange (128 MiB on
/// lavapipe): light deposits that would need more are refused with the reason, before the
/// frame's large images are made, not bound past the limit (which the validation layer
/// reports and a driver may not honour).
#[test]
fn light_deposits_beyond_the_storage_range_are_clear_errors() {
    if !on_lavapipe("the sizes below are lavapipe's limit") {
        return;
    }
    // 700² × 2 rays × 160 bytes = 157 MB of cells; their boxes (48 bytes) fit.
    assert_clean_failure(
        &[
            "render",
            "--width",
            "700",
            "--height",
            "700",
            "--volume-size",
            "16",
            "--variant",
            "deposit=cells",
            "-o",
            "x.png",
        ],
        "deposit=cells needs 160 bytes of light deposits per light ray",
    );
    // 1200² × 8 rays × 48 bytes = 553 MB even as boxes.
    assert_clean_failure(
        &[
            "render",
            "--width",
            "1200",
            "--height",
            "1200",
            "--light-rays",
            "8",
            "--volume-size",
            "16",
            "-o",
            "x.png",
        ],
        "(maxStorageBufferRange): use fewer light rays per pixel",
    );
    // 1600² × 56 bytes of the compute splat's sums = 137 MiB: any buffer bound whole
    // past the range is refused where its descriptor set is made, the buffer named.
    assert_clean_failure(
        &[
            "render",
            "--width",
            "1600",
            "--height",
            "1600",
            "--light-rays",
            "1",
            "--volume-size",
            "16",
            "-o",
            "x.png",
        ],
        "use a smaller image: descriptor set 'sweep', binding 18: buffer 'light splat sums'",
    );
}

#[test]
fn bad_environment_maps_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let corrupt = dir.path().join("corrupt.hdr");
    std::fs::write(&corrupt, b"#?RADIANCE but not really").unwrap();
    let square = dir.path().join("square.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb([9, 9, 9]))
        .save(&square)
        .unwrap();
    assert_clean_failure(
        &["render", "--env", "/no/such/map.exr", "-o", "x.png"],
        "no such file",
    );
    assert_clean_failure(
        &["render", "--env", corrupt.to_str().unwrap(), "-o", "x.png"],
        "corrupt.hdr",
    );
    assert_clean_failure(
        &["render", "--env", square.to_str().unwrap(), "-o", "x.png"],
        "twice as wide as high",
    );
    assert_clean_failure(
        &["render", "--exposure", "inf", "-o", "x.png"],
        "--exposure",
    );
}

fn image_size(path: &Path) -> (usize, usize) {
    if path.extension().unwrap() == "exr" {
        let img = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |res, _| vec![[0f32; 4]; res.width() * res.height()],
            |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                let _ = pos;
                px[0] = [r, g, b, a];
            },
        )
        .unwrap();
        let s = img.layer_data.size;
        (s.width(), s.height())
    } else {
        let bytes = std::fs::read(path).unwrap();
        // PNG IHDR: width and height are big-endian u32 at bytes 16..24.
        assert_eq!(&bytes[1..4], b"PNG");
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap()) as usize;
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap()) as usize;
        (w, h)
    }
}

#[test]
fn unknown_device_is_a_clear_error() {
    assert_clean_failure(
        &["--device", "no-such-gpu", "info"],
        "matches no Vulkan device",
    );
    assert_clean_failure(&["--device", "17", "info"], "no device with index 17");
}

#[test]
fn bad_output_paths_are_clear_errors() {
    assert_clean_failure(
        &["render", "-o", "/nonexistent-dir/x.png"],
        "does not exist",
    );
    assert_clean_failure(
        &["render", "-o", "out.jpg"],
        "unknown output extension '.jpg'",
    );
    assert_clean_failure(&["render", "-o", "out"], "needs an extension");
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("looks-like.png");
    std::fs::create_dir(&folder).unwrap();
    assert_clean_failure(&["render", "-o", folder.to_str().unwrap()], "is a folder");
}

#[test]
fn bad_sample_distances_are_clear_errors() {
    for sd in ["0", "-1", "NaN", "inf"] {
        assert_clean_failure(
            &["render", "--sample-distance", sd, "-o", "x.png"],
            "sample distance",
        );
    }
}

#[test]
fn bad_camera_and_sizes_are_clear_errors() {
    assert_clean_failure(&["render", "--width", "0", "-o", "x.png"], "image size");
    assert_clean_failure(
        &["render", "--elevation", "90.5", "-o", "x.png"],
        "elevation",
    );
    assert_clean_failure(
        &["render", "--elevation", "-91", "-o", "x.png"],
        "elevation",
    );
    assert_clean_failure(&["render", "--target", "1,2", "-o", "x.png"], "--target");
    assert_clean_failure(
        &["render", "--target", "0,NaN,0", "-o", "x.png"],
        "--target '0,NaN,0': 'NaN' is not a finite number",
    );
    assert_clean_failure(
        &["render", "--volume-size", "1", "-o", "x.png"],
        "volume size",
    );
    assert_clean_failure(
        &["render", "--background", "1,2", "-o", "x.png"],
        "--background",
    );
    // Far cameras: 1e20 made NaN light directions ("light 1: light direction [NaN...").
    assert_clean_failure(
        &["render", "--distance", "1e20", "-o", "x.png"],
        "camera distance 100000000000000000000 must be a positive number up to 1000",
    );
    assert_clean_failure(
        &["render", "--exposure", "100", "-o", "x.png"],
        "exposure 100 must be a number of stops from -64 to 64",
    );
    assert_clean_failure(
        &["photons", "--threads", "100000", "-o", "x.exr"],
        "from 1 to 1024",
    );
}

/// A light direction is a direction at any length: 1e20,1e20,0 was judged 90° from the
/// view by its overflowing length, and 1e-20,1e-20,0 "zero"; both are the light of 1,1,0.
#[test]
fn light_directions_count_at_any_length() {
    let dir = tempfile::tempdir().unwrap();
    let png = |light: &str| {
        let out = dir.path().join(format!("{}.png", light.len()));
        let o = refrakt(&[
            "render",
            "--width",
            "24",
            "--height",
            "24",
            "--volume-size",
            "16",
            "--light",
            light,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "--light {light}: {}", stderr(&o));
        std::fs::read(&out).unwrap()
    };
    let unit = png("1,1,0");
    assert!(
        png("1e20,1e20,0") == unit,
        "1e20,1e20,0 renders another light"
    );
    assert!(
        png("1e-20,1e-20,0") == unit,
        "1e-20,1e-20,0 renders another light"
    );
}

/// A mistyped REFRAKT_VALIDATE is refused, not read as "off" (validation silently gone).
#[test]
fn a_bad_validation_switch_is_an_error() {
    let o = refrakt_command(&["info"])
        .env("REFRAKT_VALIDATE", "banana")
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(!o.status.success(), "accepted REFRAKT_VALIDATE=banana");
    assert!(err.contains("REFRAKT_VALIDATE=\"banana\""), "{err}");
    let o = refrakt_command(&["info"])
        .env("REFRAKT_VALIDATE", "0")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Issue 15, item 10: a flag the EA ray marcher would ignore is an error naming it, and
/// no image is written (the README's promise: a flag that does not apply is an error).
#[test]
fn ea_refuses_the_refractive_models_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.png");
    let o = out.to_str().unwrap();
    for (flags, needle) in [
        (&["--softness", "1"][..], "--softness"),
        (&["--light", "0,1,1"][..], "--light"),
        (&["--clip", "1,0,0,0"][..], "--clip"),
        (&["--eta-scale", "2"][..], "--eta-scale"),
        (&["--light-spacing", "0.5"][..], "--light-spacing"),
        (&["--dump", "medium@1"][..], "dumps"),
        (&["--pass-timings"][..], "--pass-timings"),
        (&["--plane-flux"][..], "--plane-flux"),
    ] {
        let mut args = vec!["render", "--model", "ea", "--volume-size", "16", "-o", o];
        args.extend(flags);
        assert_clean_failure(&args, needle);
        assert!(!out.exists(), "{flags:?} left an image");
    }
    // The planes' flux per unit area is the forward transport's choice: the backward
    // step's planes hold it already.
    let args = [
        "render",
        "--light-transport",
        "backward",
        "--plane-flux",
        "--volume-size",
        "16",
        "-o",
        o,
    ];
    assert_clean_failure(&args, "forward light transport's");
    assert!(
        !out.exists(),
        "--plane-flux with the backward step left an image"
    );
}

/// Issue 17: the AO and single-scattering models take the light but not the sweep's flags; its own flags are
/// refused by the other models and checked; a good AO render writes its image.
#[test]
fn ao_takes_its_flags_and_refuses_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ao.png");
    let o = out.to_str().unwrap();
    let small = [
        "--volume-size",
        "16",
        "--width",
        "24",
        "--height",
        "24",
        "-o",
        o,
    ];
    for (model, flags, needle) in [
        ("ao", &["--softness", "1"][..], "--softness"),
        ("ao", &["--eta-scale", "2"][..], "--eta-scale"),
        ("ao", &["--dump", "medium@1"][..], "dumps"),
        ("ao", &["--ao-radius", "12"][..], "power of two"),
        ("ao", &["--ao-diffuse", "1.5"][..], "[0, 1]"),
        ("refract", &["--ao-radius", "8"][..], "--ao-radius"),
        ("ea", &["--ao-diffuse", "0.2"][..], "--ao-diffuse"),
        ("single", &["--g", "1.5"][..], "anisotropy"),
        ("single", &["--albedo", "2"][..], "albedo"),
        ("single", &["--softness", "1"][..], "--softness"),
        ("ao", &["--g", "0.3"][..], "--g"),
        ("refract", &["--albedo", "0.5"][..], "--albedo"),
    ] {
        let mut args = vec!["render", "sphere", "--model", model];
        args.extend(small);
        args.extend(flags);
        assert_clean_failure(&args, needle);
        assert!(!out.exists(), "{flags:?} left an image");
    }
    let mut args = vec!["render", "sphere", "--model", "ao"];
    args.extend(small);
    args.extend([
        "--light",
        "0,1,1",
        "--ao-radius",
        "4",
        "--ao-diffuse",
        "0.3",
    ]);
    let r = refrakt(&args);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(out.exists());
    let text = String::from_utf8_lossy(&r.stdout);
    for scope in ["extinction volume", "sat3d", "ao raymarch"] {
        assert!(text.contains(scope), "no '{scope}' timing in:\n{text}");
    }
    std::fs::remove_file(&out).unwrap();
    let mut args = vec!["render", "sphere", "--model", "single"];
    args.extend(small);
    args.extend(["--light", "0,1,1", "--g", "0.6", "--albedo", "0.8"]);
    let r = refrakt(&args);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(out.exists());
    let text = String::from_utf8_lossy(&r.stdout);
    for scope in ["transmittance cache", "single raymarch"] {
        assert!(text.contains(scope), "no '{scope}' timing in:\n{text}");
    }
}

/// Issue 15, item 9: each refusal gives its true reason, on one line.
#[test]
fn refusals_name_their_true_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("never.png");
    let o = out.to_str().unwrap();
    let one_line = |args: &[&str], needle: &str, not: &str| {
        assert_clean_failure(args, needle);
        let err = stderr(&refrakt(args));
        assert!(
            !err.contains(not),
            "{args:?}: wrong reason '{not}' in: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "not one line: {err}");
        assert!(!out.exists());
    };
    let small = ["--volume-size", "16", "--width", "16", "--height", "16"];
    let with = |extra: &[&'static str]| -> Vec<String> {
        ["render", "sphere"]
            .iter()
            .chain(&small)
            .chain(extra)
            .map(|s| s.to_string())
            .collect()
    };
    fn strs(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }
    for sd in ["300", "1e9"] {
        let mut a = with(&["--sample-distance"]);
        a.extend([sd.to_string(), "-o".into(), o.into()]);
        one_line(
            &strs(&a),
            "smaller sample distance",
            "increase the camera distance",
        );
    }
    let mut a = with(&["--spacing", "1e30,1,1", "-o"]);
    a.push(o.into());
    one_line(&strs(&a), "differ by a factor", "18446744073709551615");
    let scene = d.join("flat.toml");
    std::fs::write(
        &scene,
        "[volume]\nbuiltin = \"sphere\"\nspacing = [0, 1, 1]\n",
    )
    .unwrap();
    one_line(
        &["render", scene.to_str().unwrap(), "-o", o],
        "flat.toml",
        "no such file",
    );
    let mut a = with(&["--env"]);
    a.extend([d.to_str().unwrap().to_string(), "-o".into(), o.into()]);
    one_line(&strs(&a), "is a directory", "no such file");
    let (l1, l2) = (d.join("loop1.nrrd"), d.join("loop2.nrrd"));
    std::os::unix::fs::symlink(&l2, &l1).unwrap();
    std::os::unix::fs::symlink(&l1, &l2).unwrap();
    one_line(
        &["render", l1.to_str().unwrap(), "-o", o],
        "symbolic links",
        "no such file",
    );
    one_line(
        &["render", "sphere", "--width", "-5", "-o", o],
        "--width",
        "unexpected argument",
    );
}

/// Issue 15, item 7 and "user data shows refraction by default": a label volume whose
/// values (0..29 of 255) lie where the chosen transfer functions are transparent warns,
/// naming the data range and suggesting --window; the same volume given bare gets
/// transfer functions derived from its histogram, reported on stdout, that make it seen.
#[test]
fn empty_looking_data_warns_and_bare_volumes_get_derived_transfer_functions() {
    let dir = tempfile::tempdir().unwrap();
    let labels = dir.path().join("labels_16x16x16_uint8.raw");
    // A ball of label 29 in a background of label 0.
    let bytes: Vec<u8> = (0..16 * 16 * 16)
        .map(|i| {
            let (x, y, z) = (i % 16, (i / 16) % 16, i / 256);
            let r2 = [x, y, z]
                .iter()
                .map(|&c| (c as f32 - 7.5).powi(2))
                .sum::<f32>();
            if r2 < 36.0 {
                29
            } else {
                0
            }
        })
        .collect();
    std::fs::write(&labels, bytes).unwrap();
    let out = dir.path().join("o.exr");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "render",
            labels.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "24",
            "-o",
            out.to_str().unwrap(),
        ];
        a.extend(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |a: &[String]| refrakt(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(&args(&["--tf", "ct-bone"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("will be empty") && err.contains("0 .. 29") && err.contains("--window 0,29"),
        "no empty-image warning with the data range in: {err}"
    );
    // Bare, read as a scan (--labels off): derived transfer functions, no warning, the
    // volume visible.
    let o = run(&args(&["--labels", "off"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("derived from the histogram"), "{stdout}");
    assert!(stdout.contains("values 0 .. 29"), "{stdout}");
    assert!(!stderr(&o).contains("will be empty"), "{}", stderr(&o));
    // Bare as it is: two integer values are a label map (issue 36), coloured from the
    // palette, not derived from the histogram.
    let o = run(&args(&[]));
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("label volume: 2 labels (0 .. 29)") && !stdout.contains("histogram"),
        "{stdout}"
    );
    assert!(!stderr(&o).contains("will be empty"), "{}", stderr(&o));
}

/// `render --help` groups its options by topic, the image and the input first and the
/// developer options last, each option under its own heading; `view` shares the scene's
/// headings.
#[test]
fn help_is_grouped_by_topic_with_diagnostics_last() {
    for (cmd, headings) in [
        (
            "render",
            &[
                "Image:",
                "Input:",
                "Look:",
                "Camera:",
                "Environment:",
                "Light:",
                "Model options (each says which --model takes it):",
                "Diagnostics:",
                "Device:",
            ][..],
        ),
        (
            "view",
            &["Input:", "Look:", "Image:", "Camera:", "Light:"][..],
        ),
    ] {
        let o = refrakt(&[cmd, "--help"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let help = String::from_utf8_lossy(&o.stdout);
        let at = |h: &str| {
            help.lines()
                .position(|l| l == h)
                .unwrap_or_else(|| panic!("{cmd}: no heading {h:?} in:\n{help}"))
        };
        let positions: Vec<usize> = headings.iter().map(|h| at(h)).collect();
        assert!(
            positions.windows(2).all(|w| w[0] < w[1]),
            "{cmd}: headings out of order {headings:?} at lines {positions:?}"
        );
        // Each option sits under the heading of its topic.
        let section_of = |flag: &str| {
            let line = help
                .lines()
                .position(|l| {
                    // An option's own line: "--flag" or "-f, --flag" at its start.
                    let t = l.trim_start();
                    t.starts_with(flag) || t.get(4..).is_some_and(|r| r.starts_with(flag))
                })
                .unwrap_or_else(|| panic!("{cmd}: no {flag} in:\n{help}"));
            help.lines()
                .take(line)
                .filter(|l| l.ends_with(':') && !l.starts_with(' '))
                .last()
                .unwrap_or("")
                .to_string()
        };
        for (flag, heading) in [
            ("--width", "Image:"),
            ("--window", "Input:"),
            ("--tf", "Look:"),
            ("--azimuth", "Camera:"),
            ("--softness", "Light:"),
            ("--env ", "Environment:"),
            (
                "--albedo",
                "Model options (each says which --model takes it):",
            ),
            ("--device", "Device:"),
        ] {
            assert_eq!(section_of(flag), heading, "{cmd}: {flag}");
        }
        if cmd == "render" {
            for flag in ["--dump ", "--variant", "--pass-timings", "--verbose"] {
                assert_eq!(section_of(flag), "Diagnostics:", "render: {flag}");
            }
        }
    }
}

/// Developer diagnostics (the sweep's state traffic, its light-ray grid, its clamp
/// counts) print with -v only; the timings and the sweep's planes always.
#[test]
fn developer_diagnostics_print_with_verbose_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.png");
    let base = [
        "render",
        "--width",
        "16",
        "--height",
        "16",
        "--volume-size",
        "16",
        "-o",
        out.to_str().unwrap(),
    ];
    let diagnostics = [
        "MiB of state-buffer traffic",
        "light rays: ",
        "clamps (pixel-planes)",
    ];
    for verbose in [false, true] {
        let mut args = base.to_vec();
        if verbose {
            args.push("-v");
        }
        let o = refrakt(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        for d in diagnostics {
            assert_eq!(
                stdout.contains(d),
                verbose,
                "-v {verbose}: {d:?} in:\n{stdout}"
            );
        }
        for always in [
            "GPU time of the frame",
            " planes as ",
            " ms per plane",
            "wrote ",
        ] {
            assert!(
                stdout.contains(always),
                "-v {verbose}: no {always:?} in:\n{stdout}"
            );
        }
    }
}

/// The load line of a volume file names the type the file stores (int16 CT data were
/// once reported as "f32", the type they become on loading) and one range of values: the
/// window, when one is given, is said apart as what maps to 0 .. 1.
#[test]
fn the_load_line_names_the_stored_type_and_one_range() {
    let dir = tempfile::tempdir().unwrap();
    let ct = dir.path().join("ct_8x8x8_int16.raw");
    let values: Vec<i16> = (0..512).map(|i| -1024 + (i * 8) as i16).collect();
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&ct, bytes).unwrap();
    let out = dir.path().join("o.png");
    let (ct, out) = (ct.to_str().unwrap(), out.to_str().unwrap());
    let base = [
        "render", ct, "--model", "ea", "--width", "8", "--height", "8", "-o", out,
    ];
    for (window, expected) in [
        (None, "values -1024 .. 3064 → 0 .. 1 (no --window)"),
        (
            Some("-500,500"),
            "values -1024 .. 3064; window -500 .. 500 → 0 .. 1",
        ),
    ] {
        let mut args = base.to_vec();
        if let Some(w) = window {
            args.extend(["--window", w]);
        }
        let o = refrakt(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        let line = stdout
            .lines()
            .find(|l| l.starts_with("volume 8x8x8"))
            .unwrap_or_else(|| panic!("no load line in:\n{stdout}"));
        assert!(
            line.contains(" int16,") && line.contains(expected),
            "{window:?}: the load line {line:?} lacks \"int16\" or {expected:?}"
        );
        assert!(!line.contains("f32"), "{line}");
    }
}

/// `--list-presets` (render and view) names every preset file shipped in assets/tf/.
#[test]
fn list_presets_names_every_shipped_preset() {
    let files: Vec<String> = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/tf"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(files.len() >= 15, "{files:?}");
    for cmd in ["render", "view"] {
        let o = refrakt(&[cmd, "--list-presets"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        for f in &files {
            let line = out
                .lines()
                .find(|l| l.split_whitespace().next() == Some(f))
                .unwrap_or_else(|| panic!("{cmd}: no {f} in:\n{out}"));
            assert!(
                line.split_whitespace().count() > 2,
                "no description: {line}"
            );
        }
    }
}

/// Issue 36, item 5: `--background` applies or is an error, never ignored. With the
/// default environment (the sky) it applies: the corner of a refractive render is the
/// background's colour, where the sky's would not be; with `--env sky` (or a scene file's
/// map beside its background) it is refused. A bare volume file stands before the flat
/// background: its render equals one with `--env none` and differs from one with the sky.
#[test]
fn a_background_applies_or_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name).display().to_string();
    let small = ["--volume-size", "16", "--width", "16", "--height", "16"];
    let render = |extra: &[&str], file: &str| {
        let mut args = vec!["render"];
        args.extend(extra);
        let path = out(file);
        args.extend(["-o", path.as_str()]);
        let o = refrakt(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        image::open(&path).unwrap().to_rgb8()
    };
    let mut args = small.to_vec();
    args.extend(["--background", "1,0,0", "--tonemap", "none"]);
    let red = render(&args, "red.png");
    assert_eq!(
        red.get_pixel(0, 0).0,
        [255, 0, 0],
        "the background is not applied"
    );
    assert_clean_failure(
        &[
            "render",
            "--background",
            "1,0,0",
            "--env",
            "sky",
            "-o",
            &out("x.png"),
        ],
        "--background and --env sky",
    );
    let scene = dir.path().join("bg.toml");
    std::fs::write(
        &scene,
        "[volume]\nbuiltin = \"shell\"\nsize = 16\n[environment]\nmap = \"sky\"\n\
         [render]\nbackground = [1.0, 0.0, 0.0, 1.0]\n",
    )
    .unwrap();
    assert_clean_failure(
        &["render", scene.to_str().unwrap(), "-o", &out("x.png")],
        "background and [environment]",
    );
    // A bare volume file: a 16³ ball as a named raw file.
    let raw = dir.path().join("ball_16x16x16_uint8.raw");
    let bytes: Vec<u8> = (0..16 * 16 * 16)
        .map(|i: usize| {
            let c = [i % 16, i / 16 % 16, i / 256].map(|v| v as f32 - 7.5);
            if c.iter().map(|v| v * v).sum::<f32>() < 36.0 {
                200
            } else {
                0
            }
        })
        .collect();
    std::fs::write(&raw, bytes).unwrap();
    let r = raw.to_str().unwrap();
    let size = ["--width", "16", "--height", "16"];
    let default = render(&[&[r][..], &size].concat(), "default.png");
    let none = render(&[&[r, "--env", "none"][..], &size].concat(), "none.png");
    let sky = render(&[&[r, "--env", "sky"][..], &size].concat(), "sky.png");
    assert_eq!(
        default, none,
        "a volume file's default is not the flat background"
    );
    assert_ne!(
        default, sky,
        "the sky renders as the flat background (the test is void)"
    );
}

/// Issue 34 item 1: which model takes a flag is the model's own declaration (the
/// registry), and the error for a flag given with another model names the models that
/// take it, grouped, so the user learns where it belongs.
#[test]
fn a_flag_of_other_models_names_the_models_that_take_it() {
    let small = [
        "--volume-size",
        "8",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        "x.png",
    ];
    for (model, flags, needles) in [
        (
            "ao",
            &["--g", "0.3", "--albedo", "0.5"][..],
            &["--g, --albedo only apply to --model single, ambient, eikonal, not ao"][..],
        ),
        (
            "single",
            &["--ao-radius", "3", "--clip", "1,0,0,0"][..],
            &[
                "--ao-radius only applies to --model ao",
                "--clip only applies to --model refract",
                "not single",
            ][..],
        ),
        (
            "ea",
            &["--light", "0,1,1"][..],
            &["--light only applies to --model ao, single, ambient, refract, eikonal, not ea"][..],
        ),
        (
            "ambient",
            &["--ambient-level", "0.1,0.1,0.1"][..],
            &["--ambient-level only applies to --model refract"][..],
        ),
    ] {
        let mut args = vec!["render", "--model", model];
        args.extend(flags);
        args.extend(small);
        let o = refrakt(&args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        for n in needles {
            assert!(err.contains(n), "{args:?}: expected '{n}' in: {err}");
        }
    }
}

/// A scene file's settings of other models are refused as their flags are (they were
/// silently ignored), and so are the light rays' settings with the backward transport,
/// from a file or the command line (they were ignored: the images were byte-identical).
#[test]
fn settings_that_do_not_apply_are_refused_from_files_and_flags() {
    let dir = tempfile::tempdir().unwrap();
    let head = "[volume]\nbuiltin = \"shell\"\nsize = 8\n[render]\nwidth = 8\nheight = 8\n";
    for (body, needle) in [
        (
            "model = \"ea\"\n[light]\ntowards = [0, 1, 1]\nsoftness = 2\n",
            "[light] softness, [light] towards only apply to --model ao, single, ambient, \
             refract, eikonal, not ea",
        ),
        (
            "model = \"ea\"\n[environment]\nmap = \"sky\"\nrotation = 30\n",
            "[environment] map, [environment] rotation only apply to --model refract, eikonal",
        ),
        (
            "model = \"refract\"\ng = 0.5\nalbedo = 0.2\n",
            "[render] g, [render] albedo only apply to --model single, ambient, eikonal, not refract",
        ),
        (
            "light_transport = \"backward\"\nlight_rays = 8\nlight_spacing = 4\n",
            "[render] light_rays, [render] light_spacing only apply to the forward light \
             transport",
        ),
    ] {
        let path = dir.path().join("s.toml");
        std::fs::write(&path, format!("{head}{body}")).unwrap();
        let out = dir.path().join("o.png");
        let o = refrakt(&[
            "render",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(needle), "{body}: {err}");
        assert!(!out.exists(), "{body}: an image was written");
    }
    // An 8³ volume rendered at 8 × 8 with these settings.
    let tiny = |settings: &[&'static str]| -> Vec<&'static str> {
        let mut args = vec![
            "render",
            "--volume-size",
            "8",
            "--width",
            "8",
            "--height",
            "8",
        ];
        args.extend_from_slice(settings);
        args.extend_from_slice(&["-o", "x.png"]);
        args
    };
    assert_clean_failure(
        &tiny(&["--light-transport", "backward", "--light-rays", "4"]),
        "--light-rays only applies to the forward light transport",
    );
    // The eikonal transport's light is the simulator's: no softness filter, and nothing
    // on the planes to dump.
    assert_clean_failure(
        &tiny(&["--light-transport", "eikonal", "--softness", "1"]),
        "--softness does not apply to the eikonal light transport",
    );
    assert_clean_failure(
        &tiny(&["--light-transport", "eikonal", "--dump", "light-colour@1"]),
        "the light is in the light volume, not on the planes",
    );
}

/// A stand-in too large for the device is refused before it is generated (`--scale 2` on
/// the glass wrote 3.8 GB to the cache first), and one too small is refused, not raised
/// to 2 voxels a side while the report names the scale asked for.
#[test]
fn stand_in_scales_are_checked_before_any_work() {
    // On lavapipe (2 GiB for textures): a GPU may hold the 3.8 GB volume, and then make it.
    if !on_lavapipe("the size below is beyond lavapipe's limit only") {
        return;
    }
    let cache = tempfile::tempdir().unwrap();
    let run = |scale: &str| {
        refrakt_command(&[
            "--device", "llvmpipe", "render", "glass", "--scale", scale, "--width", "8",
            "--height", "8", "-o", "x.png",
        ])
        .env("REFRAKT_CACHE_DIR", cache.path())
        .output()
        .unwrap()
    };
    let o = run("2");
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("the glass stand-in at scale 2"),
        "{err}"
    );
    assert!(
        std::fs::read_dir(cache.path()).unwrap().next().is_none(),
        "something was written to the cache"
    );
    let o = run("0.001");
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("fewer than 2 along an axis"),
        "{err}"
    );
}

/// Values that used to be accepted and then ignored (or half used) are refused, naming the
/// reason.
#[test]
fn settings_that_would_be_ignored_are_refused() {
    let small = [
        "--volume-size",
        "8",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        "x.png",
    ];
    for (args, needle) in [
        (
            &["--upright", "off"][..],
            "--upright applies to volume files",
        ),
        (
            &["--env", "none", "--env-rotation", "30"][..],
            "an environment rotation (30°) turns an environment map, and this scene has none",
        ),
        (
            &["--background", "1,0,0", "--env-rotation", "30"][..],
            "this scene has none",
        ),
        (
            &["--dump-dir", "."][..],
            "--dump-dir is where --dump writes",
        ),
        (
            &["--variant", "region=full,region=rect"][..],
            "'region' is given twice",
        ),
        (
            &["--background", "1,0,0,2"][..],
            "the alpha 2 must be between 0 and 1",
        ),
        (
            &["--background", "nan,0,0"][..],
            "'nan' is not a finite, non-negative number",
        ),
    ] {
        let mut a = vec!["render"];
        a.extend(args);
        a.extend(small);
        assert_clean_failure(&a, needle);
    }
    assert_clean_failure(&["--device", "", "info"], "--device '' is empty");
}

/// `render` with the eikonal light simulation (the eikonal model, the sweep's eikonal
/// transport) prints each light's simulation summary, and its accounting is physics: in
/// a volume of clear air all the launched light leaves the box (none absorbed, torn or
/// diluted), in one of opaque matter none does, and through the sphere-on-floor scene
/// (its floor a slab narrower than the box) some does not.
#[test]
fn render_prints_where_the_simulated_light_went() {
    let dir = tempfile::tempdir().unwrap();
    let tf = |name: &str, opacity: f32| {
        let path = dir.path().join(name);
        let text = format!("colour = [[0.0, 1, 1, 1]]\nopacity = [[0.0, {opacity}]]\n");
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let (air, opaque) = (tf("air.toml", 0.0), tf("opaque.toml", 1.0));
    let out = dir.path().join("x.png");
    let left_the_box = |extra: &[&str]| -> f64 {
        let mut args = vec![
            "render",
            "--volume-size",
            "12",
            "--width",
            "16",
            "--height",
            "16",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = refrakt(&args);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let line = text
            .lines()
            .find(|l| l.starts_with("light simulation, light 1: "))
            .unwrap_or_else(|| panic!("{args:?}: no simulation summary in:\n{text}"));
        let left: f64 = line
            .split(" % left the box")
            .next()
            .and_then(|s| s.rsplit(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no share that left the box in: {line}"));
        eprintln!("{args:?}: {line}");
        left
    };
    let clear = left_the_box(&["--model", "eikonal", "--tf", &air]);
    assert!(clear > 99.9, "in clear air {clear} % left the box");
    let dark = left_the_box(&["--model", "eikonal", "--tf", &opaque]);
    assert!(dark < 0.1, "through opaque matter {dark} % left the box");
    let floor = left_the_box(&["--light-transport", "eikonal"]);
    assert!(
        (1.0..99.0).contains(&floor),
        "past the sphere on its floor {floor} % left the box"
    );
}

/// `--abbe` (dispersion): the eikonal model simulates the light once per colour channel
/// and says so, each wavefront's line naming its channel and wavelength; other models
/// refuse it naming the one that takes it, and an Abbe number outside 5–1000 (not 0) is
/// refused with the range. Scene files take it as `abbe`.
#[test]
fn abbe_splits_the_light_by_colour_and_is_refused_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let small = [
        "--volume-size",
        "12",
        "--width",
        "16",
        "--height",
        "16",
        "-o",
        out.to_str().unwrap(),
    ];
    let mut args = vec!["render", "--model", "eikonal", "--abbe", "40"];
    args.extend_from_slice(&small);
    let o = refrakt(&args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("light simulation, light 1"))
        .collect();
    let prefixes: Vec<&str> = lines.iter().map(|l| l.split(':').next().unwrap()).collect();
    assert_eq!(
        prefixes,
        [
            "light simulation, light 1, red (656 nm)",
            "light simulation, light 1, green (588 nm)",
            "light simulation, light 1, blue (486 nm)"
        ],
        "{text}"
    );
    for (model, needle) in [
        ("refract", "--abbe only applies to --model eikonal"),
        (
            "eikonal",
            "the Abbe number must be 0 (no dispersion) or from 5 to 1000",
        ),
    ] {
        let value = if model == "eikonal" { "3" } else { "40" };
        let mut a = vec!["render", "--model", model, "--abbe", value];
        a.extend_from_slice(&small);
        assert_clean_failure(&a, needle);
    }
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "[volume]\nbuiltin = \"shell\"\nsize = 8\n[render]\nmodel = \"refract\"\nabbe = 30\n",
    )
    .unwrap();
    let a = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    assert_clean_failure(
        &a,
        "[render] abbe only applies to --model eikonal, not refract",
    );
}

/// `--cubic-eta` (scene key `cubic_eta`): the eikonal model takes η from the cubic
/// B-spline (a glass ball then looks different: its view through the glass is no longer
/// scattered by the trilinear field's corrugation), refuses any value but 0 and 1, and
/// other models refuse the flag.
#[test]
fn cubic_eta_from_a_flag_or_a_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let png = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let small = ["--volume-size", "16", "--width", "24", "--height", "24"];
    let render_with = |extra: &[&str], out: &str| {
        let mut a = vec!["render", "--model", "eikonal"];
        a.extend_from_slice(&small);
        a.extend_from_slice(extra);
        a.extend_from_slice(&["-o", out]);
        let o = refrakt(&a);
        assert!(o.status.success(), "{a:?}: {}", stderr(&o));
        image::open(out).unwrap().to_rgb8()
    };
    let trilinear = render_with(&[], &png("t.png"));
    let cubic = render_with(&["--cubic-eta", "1"], &png("c.png"));
    let differ = trilinear
        .pixels()
        .zip(cubic.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 3))
        .count();
    assert!(differ > 10, "cubic eta changed only {differ} pixels");
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "[volume]\nbuiltin = \"sphere-on-floor\"\nsize = 16\n[render]\nmodel = \"eikonal\"\n\
         cubic_eta = 1\nwidth = 24\nheight = 24\n",
    )
    .unwrap();
    let from_scene = png("s.png");
    let o = refrakt(&["render", scene.to_str().unwrap(), "-o", &from_scene]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        image::open(&from_scene).unwrap().to_rgb8().as_raw(),
        cubic.as_raw(),
        "the scene key gave another image than the flag"
    );
    let out = png("x.png");
    for (model, value, needle) in [
        (
            "eikonal",
            "2",
            "--cubic-eta: 0 (trilinear) or 1 (cubic B-spline) only",
        ),
        (
            "refract",
            "1",
            "--cubic-eta only applies to --model eikonal",
        ),
    ] {
        let mut a = vec!["render", "--model", model, "--cubic-eta", value];
        a.extend_from_slice(&small);
        a.extend_from_slice(&["-o", &out]);
        assert_clean_failure(&a, needle);
    }
}

/// What the reflected part sees, from a flag or a scene file: `--reflections volume` (the
/// default, also `on`) and `environment`, `reflections = "volume"` / `"environment"` in
/// `[render]` give the same frames as the flags (to the byte), the two differ where the
/// glass reflects the floor, and a word that is neither is refused naming the key.
#[test]
fn reflections_volume_or_environment_from_flags_and_files() {
    let dir = tempfile::tempdir().unwrap();
    // The sphere on its floor seen from 8° above: its lower half mirrors the floor.
    let scene = |name: &str, key: &str| {
        let path = dir.path().join(format!("{name}.toml"));
        std::fs::write(
            &path,
            format!(
                "[volume]\nbuiltin = \"sphere-on-floor\"\nsize = 24\n[camera]\nelevation = 8\n\
                 [render]\nwidth = 24\nheight = 24\n{key}"
            ),
        )
        .unwrap();
        path
    };
    let plain = scene("plain", "");
    let render = |file: &Path, flags: &[&str], name: &str| -> Vec<u8> {
        let out = dir.path().join(name);
        let mut args = vec!["render", file.to_str().unwrap()];
        args.extend_from_slice(flags);
        args.extend_from_slice(&["-o", out.to_str().unwrap()]);
        let o = refrakt(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        std::fs::read(&out).unwrap()
    };
    let default = render(&plain, &[], "default.png");
    let on = render(&plain, &["--reflections", "on"], "on.png");
    let volume = render(&plain, &["--reflections", "volume"], "volume.png");
    let environment = render(&plain, &["--reflections", "environment"], "environment.png");
    assert!(default == volume && on == volume, "the default is volume");
    assert!(
        volume != environment,
        "the glass reflects the floor, not only the sky"
    );
    for (value, want) in [("\"volume\"", &volume), ("\"environment\"", &environment)] {
        let file = scene("keyed", &format!("reflections = {value}\n"));
        let from_file = render(&file, &[], "file.png");
        assert!(&from_file == want, "reflections = {value} in a scene file");
    }
    let file = scene("bad", "reflections = \"mirror\"\n");
    assert_clean_failure(
        &["render", file.to_str().unwrap(), "-o", "x.png"],
        "[render] reflections = \"mirror\": give true, false, \"volume\" or \"environment\"",
    );
}

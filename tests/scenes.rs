//! Issue 6: scene files, built-in scenes, command-line overrides, and the errors a user
//! meets with bad scene files or volumes too large for the device.

mod common;
#[path = "common/samples.rs"]
mod samples;

use samples::SMALL;
use std::path::Path;

use common::{refrakt, with_context};
use refrakt::render::Renderer;
use refrakt::scene::Scene;
use refrakt::transfer::TransferFunctions;
use refrakt::volume::{Volume, Voxels};

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// Fails unless the command failed cleanly, said `needles`, and wrote no output file.
fn fails_with(args: &[&str], out: &Path, needles: &[&str]) {
    let o = refrakt(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "expected '{n}' in: {err}");
    }
    assert_eq!(err.trim().lines().count(), 1, "not one line: {err}");
    assert!(
        !out.exists(),
        "partial output {} left behind",
        out.display()
    );
}

#[test]
fn scene_file_sets_everything_and_flags_override_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "tiny.toml", SMALL);
    let out = dir.path().join("a.png");
    let o = refrakt(&["render", &scene, "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("tiny"), "{stdout}");
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (24, 20));
    // The camera looks at the centre of a sphere that the inline transfer function makes
    // opaque red; the corner sees the scene's blue background.
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 255]);
    let c = img.get_pixel(12, 10).0;
    // (Lit head-on, an opaque surface returns half the light: the self-shadowing of its
    // skin, 1 / (1 + r) with r = 1.)
    assert!(c[0] > 120 && c[1] < 30 && c[2] < 30, "centre {c:?}");

    // Flags override fields: size, background, and the environment.
    let out2 = dir.path().join("b.png");
    let o = refrakt(&[
        "render",
        &scene,
        "-o",
        out2.to_str().unwrap(),
        "--width",
        "16",
        "--background",
        "0,1,0",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out2).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (16, 20));
    assert_eq!(img.get_pixel(0, 0).0, [0, 255, 0]);
}

/// Mean pixel position (x, y) of the opaque red sphere of [`SMALL`].
fn red_centroid(path: &Path) -> (f64, f64) {
    let img = image::open(path).unwrap().to_rgb8();
    let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for (x, y, p) in img.enumerate_pixels() {
        if p.0[0] > 150 {
            n += 1.0;
            sx += x as f64 + 0.5;
            sy += y as f64 + 0.5;
        }
    }
    assert!(n > 20.0, "{}: only {n} red pixels", path.display());
    (sx / n, sy / n)
}

fn render_ok(args: &[&str]) {
    let o = refrakt(args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn the_camera_looks_at_its_target_from_flags_and_scene_files() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "tiny.toml", SMALL);
    let png = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    // SMALL: 24x20 pixels, fov 30, eye 2.5 in front of the sphere at the origin; 0.1 world
    // units at the sphere's depth are 10 / (2.5 tan 15°) / 10 = 1.49 pixels.
    let px_per_unit = 10.0 / (2.5 * 15f64.to_radians().tan());
    render_ok(&["render", &scene, "-o", &png("origin.png")]);
    let (x0, y0) = red_centroid(Path::new(&png("origin.png")));

    // Looking at a point right of the sphere: the camera moves with its target, so the
    // sphere moves left in the image, as far as the target is from it.
    render_ok(&[
        "render",
        &scene,
        "--target",
        "0.3,0,0",
        "-o",
        &png("flag.png"),
    ]);
    let (x1, y1) = red_centroid(Path::new(&png("flag.png")));
    assert!((x1 - (x0 - 0.3 * px_per_unit)).abs() < 1.0, "{x0} -> {x1}");
    assert!((y1 - y0).abs() < 0.5, "{y0} -> {y1}");

    // The same camera from a scene file, with eye and target or angles and target.
    let flag = std::fs::read(png("flag.png")).unwrap();
    for (i, camera) in [
        "eye = [0.3, 0.0, 2.5]\ntarget = [0.3, 0.0, 0.0]",
        "azimuth = 0\nelevation = 0\ndistance = 2.5\ntarget = [0.3, 0, 0]",
    ]
    .iter()
    .enumerate()
    {
        let file = write(
            dir.path(),
            &format!("t{i}.toml"),
            &SMALL.replace("eye = [0.0, 0.0, 2.5]", camera),
        );
        render_ok(&["render", &file, "-o", &png(&format!("t{i}.png"))]);
        assert!(
            std::fs::read(png(&format!("t{i}.png"))).unwrap() == flag,
            "scene file camera {camera:?} renders differently from --target"
        );
    }

    // Straight down (elevation 90) at a target 0.2 in front of the sphere (+z): at azimuth
    // 0 screen-up is -z, so the sphere lies above the image centre.
    render_ok(&[
        "render",
        &scene,
        "--elevation",
        "90",
        "--target",
        "0,0,0.2",
        "-o",
        &png("down.png"),
    ]);
    let (x2, y2) = red_centroid(Path::new(&png("down.png")));
    assert!((x2 - x0).abs() < 0.5, "{x0} -> {x2}");
    assert!((y2 - (10.0 - 0.2 * px_per_unit)).abs() < 1.0, "{y2}");
    // An eye straight above the target is the same view.
    let file = write(
        dir.path(),
        "above.toml",
        &SMALL.replace(
            "eye = [0.0, 0.0, 2.5]",
            "eye = [0.0, 2.5, 0.2]\ntarget = [0.0, 0.0, 0.2]",
        ),
    );
    render_ok(&["render", &file, "-o", &png("above.png")]);
    assert!(std::fs::read(png("above.png")).unwrap() == std::fs::read(png("down.png")).unwrap());
}

#[test]
fn bad_scene_files_are_one_line_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.png");
    let o = out.to_str().unwrap();
    let unknown = write(
        dir.path(),
        "unknown.toml",
        &SMALL.replace("fov = 30", "fov = 30\nzoom = 2"),
    );
    fails_with(
        &["render", &unknown, "-o", o],
        &out,
        &["unknown.toml", "zoom"],
    );
    let wrong = write(
        dir.path(),
        "wrong.toml",
        &SMALL.replace("width = 24", "width = \"wide\""),
    );
    fails_with(&["render", &wrong, "-o", o], &out, &["wrong.toml", "width"]);
    let missing = write(
        dir.path(),
        "missing.toml",
        "[volume]\nfile = \"no-such-volume.nrrd\"\n",
    );
    fails_with(
        &["render", &missing, "-o", o],
        &out,
        &["missing.toml", "no-such-volume.nrrd", "not found"],
    );
    let env = write(
        dir.path(),
        "env.toml",
        &SMALL.replace("map = \"none\"", "map = \"sky-that-is-not-here.exr\""),
    );
    fails_with(
        &["render", &env, "-o", o],
        &out,
        &["env.toml", "sky-that-is-not-here.exr"],
    );
    let bad_camera = write(
        dir.path(),
        "cam.toml",
        &SMALL.replace(
            "eye = [0.0, 0.0, 2.5]",
            "eye = [0.0, 0.0, 2.5]\nazimuth = 3",
        ),
    );
    fails_with(
        &["render", &bad_camera, "-o", o],
        &out,
        &["cam.toml", "eye"],
    );
    let bad_target = write(
        dir.path(),
        "target.toml",
        &SMALL.replace("fov = 30", "fov = 30\ntarget = [0.0, nan, 0.0]"),
    );
    fails_with(
        &["render", &bad_target, "-o", o],
        &out,
        &["target.toml", "[camera] target", "finite"],
    );
    let short_target = write(
        dir.path(),
        "short.toml",
        &SMALL.replace("fov = 30", "fov = 30\ntarget = [0.0, 1.0]"),
    );
    fails_with(
        &["render", &short_target, "-o", o],
        &out,
        &["short.toml", "target"],
    );
    fails_with(
        &["render", "no-such-scene", "-o", o],
        &out,
        &["no-such-scene", "not a built-in scene", "sphere-on-floor"],
    );
    fails_with(
        &["render", "sphere-on-floor", "--scale", "0.5", "-o", o],
        &out,
        &["--scale", "stand-ins"],
    );
}

#[test]
fn every_builtin_scene_resolves_with_its_preset() {
    for (name, _) in refrakt::scene::builtin_names() {
        let s = Scene::resolve(&name).unwrap();
        s.transfer_functions()
            .unwrap_or_else(|e| panic!("{name}: {e:#}"));
        s.render_options()
            .unwrap_or_else(|e| panic!("{name}: {e:#}"));
    }
    let glass = Scene::resolve("glass").unwrap();
    assert_eq!(glass.transfer_functions().unwrap().name, "glass-scene");
    assert_eq!((glass.width, glass.height), (768, 768));
}

#[test]
fn volumes_beyond_the_device_limit_are_refused_naming_it() {
    with_context(|ctx| {
        let max = ctx.info().limits.max_image_dimension3_d;
        let dims = [max + 1, 2, 2];
        let n = dims.iter().map(|&d| d as usize).product();
        let vol = Volume::new(dims, [1.0; 3], Voxels::U8(vec![0; n])).unwrap();
        let tf = TransferFunctions::load("ct-bone").unwrap();
        let err = format!("{:#}", Renderer::new(ctx, &vol, &tf).err().unwrap());
        assert!(
            err.contains(&max.to_string()) && err.contains("maxImageDimension3D"),
            "{err}"
        );
    });
}

#[test]
fn the_readme_scene_file_example_parses() {
    let readme = include_str!("../README.md");
    let start = readme
        .find("```toml\nname = \"ct-demo\"")
        .expect("README has the scene file example");
    let body = &readme[start + "```toml\n".len()..];
    let text = &body[..body.find("```").unwrap()];
    let dir = tempfile::tempdir().unwrap();
    // The example names a volume file next to it; the parser checks it exists.
    std::fs::write(dir.path().join("lung1_image.nrrd"), b"").unwrap();
    let s = Scene::parse(text, &dir.path().join("ct-demo.toml")).unwrap();
    assert_eq!(s.name, "ct-demo");
    assert_eq!((s.width, s.height), (512, 512));
    assert_eq!(s.camera.azimuth, 20.0);
    assert_eq!(s.clip.map(|c| c.1), Some(0.0));
    assert_eq!(s.transfer_functions().unwrap().name, "lung-ct");
}

/// The real scenes load their fetched scans (scripts/fetch-data; required in CI).
#[test]
fn real_scenes_load_their_scans() {
    let dir = refrakt::scene::data_dir();
    for (name, dims) in [("lung-ct", [512, 512, 48]), ("mri-head", [181, 217, 181])] {
        let s = Scene::resolve(name).unwrap();
        match s.load_volume(&dir, None) {
            Ok(v) => {
                assert_eq!(v.dims, dims, "{name}");
                // The CT's 5 mm slices and 0.57 mm pixels survive into the spacing.
                if name == "lung-ct" {
                    assert!((v.spacing[2] / v.spacing[0] - 5.0 / 0.5703125).abs() < 1e-3);
                }
            }
            Err(e) => {
                let e = format!("{e:#}");
                assert!(
                    std::env::var("REFRAKT_REQUIRE_DATA").is_err() && e.contains("fetch-data"),
                    "{name}: {e}"
                );
                println!("skipped {name}: {e}");
            }
        }
    }
}

#[test]
fn generate_names_unknown_stand_ins() {
    let o = refrakt(&["generate", "teapot"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("teapot") && err.contains("kiwi"),
        "{err}"
    );
}

/// Bad volume files through the command line: one line naming the file and the reason,
/// a non-zero exit, no panic, no output image.
#[test]
fn bad_volume_files_fail_cleanly_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.png");
    let o = out.to_str().unwrap();
    // 4x4x4 u8 needs 64 bytes; 60 given.
    let short = dir.path().join("short_4x4x4_uint8.raw");
    std::fs::write(&short, [0u8; 60]).unwrap();
    fails_with(
        &["render", short.to_str().unwrap(), "-o", o],
        &out,
        &["short_4x4x4_uint8.raw", "64"],
    );
    // dims x type that do not match an explicit raw file's size.
    let raw = dir.path().join("scan.bin");
    std::fs::write(&raw, [0u8; 100]).unwrap();
    fails_with(
        &[
            "render",
            raw.to_str().unwrap(),
            "--dims",
            "4,4,4",
            "--type",
            "u16",
            "-o",
            o,
        ],
        &out,
        &["scan.bin", "128"],
    );
    let nii = dir.path().join("bad.nii");
    let mut hdr = vec![0u8; 400];
    hdr[..4].copy_from_slice(&348i32.to_le_bytes());
    hdr[344..348].copy_from_slice(b"xy1\0");
    std::fs::write(&nii, hdr).unwrap();
    fails_with(
        &["render", nii.to_str().unwrap(), "-o", o],
        &out,
        &["bad.nii", "magic"],
    );
    let nrrd = dir.path().join("bz.nrrd");
    std::fs::write(
        &nrrd,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n\nxxxx",
    )
    .unwrap();
    fails_with(
        &["render", nrrd.to_str().unwrap(), "-o", o],
        &out,
        &["bz.nrrd", "bzip2"],
    );
}

/// Issue 15, items 1–4: hostile volume inputs are refused from their headers, cheaply.
/// Sparse files stand in for big ones: reading one in full would take seconds and
/// gigabytes, which the time bound catches (each refusal here takes ~0.2 s).
#[test]
fn huge_endless_and_special_inputs_are_refused_before_reading() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("never.png");
    let o = out.to_str().unwrap();
    let quick = |args: &[&str], needles: &[&str]| {
        let t = Instant::now();
        fails_with(args, &out, needles);
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "{args:?} took {:?}",
            t.elapsed()
        );
    };
    let nhdr = |name: &str, sizes: &str, data: &str| {
        let p = d.join(name);
        std::fs::write(
            &p,
            format!(
                "NRRD0004\ntype: uint8\ndimension: 3\nsizes: {sizes}\nencoding: raw\n\
                 data file: {data}\n\n"
            ),
        )
        .unwrap();
        p.to_str().unwrap().to_owned()
    };
    // 1. Detached data from an endless device, 8 GB promised: the device cannot hold it
    // (lavapipe: 2 GiB heap), so the header alone refuses it.
    let zero = nhdr("zero.nhdr", "2000 2000 2000", "/dev/zero");
    quick(
        &["render", &zero, "-o", o],
        &["zero.nhdr", "from the header"],
    );
    // ... and a small volume from it is refused as no regular file (it would never end).
    let zero_small = nhdr("small.nhdr", "8 8 8", "/dev/zero");
    quick(
        &["render", &zero_small, "-o", o],
        &["small.nhdr", "/dev/zero", "not a regular file"],
    );
    // 1. A detached file longer than the header promises is not read past the promise.
    let long = d.join("long.raw");
    std::fs::File::create(&long)
        .unwrap()
        .set_len(20_000_000_000)
        .unwrap();
    let long_hdr = nhdr("long.nhdr", "8 8 8", "long.raw");
    quick(
        &["render", &long_hdr, "-o", o],
        &[
            "long.nhdr",
            "long.raw",
            "20000000000 bytes",
            "promises 512 bytes",
        ],
    );
    // 3. A FIFO would block forever.
    let fifo = d.join("pipe.nrrd");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    quick(
        &["render", fifo.to_str().unwrap(), "-o", o],
        &["pipe.nrrd", "FIFO"],
    );
    // 4. 4096×4096×160 u8 (2.7 GB): refused from the name's dimensions.
    let big = d.join("big_4096x4096x160_uint8.raw");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(4096 * 4096 * 160)
        .unwrap();
    quick(
        &["render", big.to_str().unwrap(), "-o", o],
        &["big_4096x4096x160_uint8.raw", "from the header"],
    );
    // 2. A folder of large files that are not DICOM: only their first bytes are read.
    let folder = d.join("not-dicom");
    std::fs::create_dir(&folder).unwrap();
    for i in 0..20 {
        std::fs::File::create(folder.join(format!("f{i}.bin")))
            .unwrap()
            .set_len(500_000_000)
            .unwrap();
    }
    quick(
        &["render", folder.to_str().unwrap(), "-o", o],
        &["not-dicom", "no DICOM image files found"],
    );
}

/// Issue 15, item 8: an error is one bounded line whatever the file quotes: a 1 MB
/// garbage scene file, a TOML error (four lines from the parser), a header of NUL bytes.
#[test]
fn errors_quoting_garbage_stay_one_short_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("never.png");
    let o = out.to_str().unwrap();
    let short_line = |args: &[&str], needles: &[&str]| {
        let r = refrakt(args);
        let err = String::from_utf8_lossy(&r.stderr).to_string();
        fails_with(args, &out, needles);
        assert!(err.len() < 600, "{} bytes of error", err.len());
        assert!(
            !err.trim_end().contains(['\0', '\r']),
            "control bytes in {err:?}"
        );
    };
    let garbage = d.join("garbage.toml");
    std::fs::write(&garbage, "x".repeat(1 << 20) + " = = [").unwrap();
    short_line(
        &["render", garbage.to_str().unwrap(), "-o", o],
        &["garbage.toml", "characters cut"],
    );
    let bad = d.join("bad.toml");
    std::fs::write(&bad, "[camera]\nfov = \"wide\"\n").unwrap();
    short_line(
        &["render", bad.to_str().unwrap(), "-o", o],
        &["bad.toml", "fov"],
    );
    let nuls = d.join("nuls.nrrd");
    let mut bytes = b"NRRD0004\n".to_vec();
    bytes.extend([0u8; 512]);
    std::fs::write(&nuls, bytes).unwrap();
    short_line(
        &["render", nuls.to_str().unwrap(), "-o", o],
        &["nuls.nrrd", "\\u{0}"],
    );
}

#[test]
fn flip_axes_parse_or_fail_clearly() {
    let p = Path::new("f.toml");
    let s = Scene::parse("[volume]\nbuiltin = \"sphere\"\nflip = \"xz\"\n", p).unwrap();
    assert_eq!(s.flip, [true, false, true]);
    for bad in ["xq", "xx", ""] {
        let text = format!("[volume]\nbuiltin = \"sphere\"\nflip = \"{bad}\"\n");
        let e = format!("{:#}", Scene::parse(&text, p).unwrap_err());
        assert!(e.contains("f.toml") && e.contains("flip"), "{e}");
    }
}

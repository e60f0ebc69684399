//! `refrakt view` (issue 8). The GPU tone-map pass the window shows must equal the PNG
//! path's CPU tone mapping (headless, always runs), and the viewer itself, in a real X11
//! window under Xvfb with validation on, must run frames, survive a resize and take a
//! screenshot equal to the headless render of the same scene and camera within 1/255.
//!
//! The window test starts its own `Xvfb` (a free display picked by Xvfb itself,
//! `-displayfd`) when DISPLAY is unset, and kills it at the end. Without Xvfb it prints a
//! skip line, or fails when REFRAKT_REQUIRE_DISPLAY=1 (CI sets up Xvfb with
//! scripts/setup.sh).

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

use refrakt::output::{self, ToneMap, ToneOperator};
use refrakt::render::{Camera, Model, RenderOptions, Renderer, Slot, ToneMapPass};
use refrakt::transfer::TransferFunctions;
use refrakt::vk::{self, Framebuffer, Image, ImageDesc, ImageKind};
use refrakt::volume::procedural;

/// The tests of this file one at a time: the preview test reads frame times, which other
/// renders on the same CPU cores would stretch.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn exclusive() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// Tone map `frame` with the GPU pass into an RGBA8 UNORM image and read it back.
fn gpu_tonemap(
    ctx: &vk::Context,
    renderer: &mut Renderer,
    model: Model,
    camera: &Camera,
    opts: &RenderOptions,
    tone: &ToneMap,
) -> (Vec<u8>, Vec<[f32; 4]>) {
    let target = Image::new(
        ctx,
        ImageDesc {
            kind: ImageKind::D2,
            format: vk::Format::R8G8B8A8_UNORM,
            extent: [opts.width, opts.height, 1],
            layers: 1,
            usage: vk::usage::COLOR_ATTACHMENT | vk::usage::TRANSFER_SRC,
        },
        "tonemap target",
    )
    .unwrap();
    let mut pass = ToneMapPass::new(ctx, vk::Format::R8G8B8A8_UNORM, false).unwrap();
    let view = target.layer_view(0).unwrap();
    let fb = Framebuffer::new(
        ctx,
        pass.render_pass(),
        &[&view],
        opts.width,
        opts.height,
        "tonemap fb",
    )
    .unwrap();
    let linear = renderer.render(model, camera, opts).unwrap().pixels;
    ctx.execute(|rec| {
        let out = renderer.record(rec, Slot::Main, model, camera, opts)?;
        pass.record(rec, out.image, &target, &fb, tone, None)
    })
    .unwrap();
    (ctx.read_image(&target, 0).unwrap(), linear)
}

fn max_difference(a: &[u8], b: &[u8]) -> (u8, usize) {
    assert_eq!(a.len(), b.len());
    let mut worst = (0u8, 0usize);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let d = x.abs_diff(*y);
        if d > worst.0 {
            worst = (d, i);
        }
    }
    worst
}

#[test]
fn gpu_tone_mapping_matches_the_png_path() {
    let _one = exclusive();
    common::with_context(|ctx| {
        let volume = procedural::sphere_on_floor(24).unwrap();
        let tf = TransferFunctions::load("glass-floor").unwrap();
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        let env = refrakt::environment::EnvironmentMap::procedural(256).unwrap();
        renderer.set_environment(Some(&env)).unwrap();
        let camera = Camera::default();
        let opts = RenderOptions {
            width: 48,
            height: 40,
            ..Default::default()
        };
        // Every operator, and exposures that push much of the image past 1 and far below.
        for tone in [
            ToneMap::default(),
            ToneMap {
                exposure: 1.5,
                operator: ToneOperator::Reinhard,
            },
            ToneMap {
                exposure: -2.0,
                operator: ToneOperator::None,
            },
            ToneMap {
                exposure: 3.0,
                operator: ToneOperator::Aces,
            },
        ] {
            for model in [Model::Refract, Model::Ea] {
                let (gpu, linear) = gpu_tonemap(ctx, &mut renderer, model, &camera, &opts, &tone);
                let frame = refrakt::render::Frame {
                    width: opts.width,
                    height: opts.height,
                    pixels: linear,
                    timings: Default::default(),
                    max_steps: 0,
                    dumps: Vec::new(),
                    sweep: None,
                };
                let cpu = output::to_srgb8(&frame, &tone);
                let (d, at) = max_difference(&gpu, &cpu);
                assert!(
                    d <= 1,
                    "{tone:?} {model:?}: GPU {} vs CPU {} at byte {at} (pixel {:?})",
                    gpu[at],
                    cpu[at],
                    frame.pixels[at / 4]
                );
            }
        }
    });
}

#[test]
fn recorded_frames_equal_rendered_frames() {
    let _one = exclusive();
    // Renderer::record (the viewer's path) leaves in its image exactly what render reads
    // back, also when several recordings with different cameras and models share one
    // submission: each frame's parameters travel in the command stream (a parameter
    // buffer written on the host would hold the last frame's for all of them) and each
    // copy sees its own frame (the barriers between frames).
    common::with_context(|ctx| {
        let volume = procedural::sphere(20, 0.35, 1.0).unwrap();
        let tf = TransferFunctions::load("glass").unwrap();
        let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
        let first = Camera::default();
        let second = Camera {
            azimuth: first.azimuth + 15.0,
            elevation: first.elevation + 10.0,
            ..first
        };
        let opts = RenderOptions {
            width: 24,
            height: 20,
            ..Default::default()
        };
        let expected_ea = renderer.render(Model::Ea, &second, &opts).unwrap();
        let expected_first = renderer.render(Model::Refract, &first, &opts).unwrap();
        let expected_second = renderer.render(Model::Refract, &second, &opts).unwrap();
        assert_ne!(
            expected_first.pixels, expected_second.pixels,
            "the two cameras must see different images for this test to mean anything"
        );
        let bytes = 24 * 20 * 16;
        let readbacks: Vec<vk::Buffer> = (0..3)
            .map(|i| vk::Buffer::readback(ctx, bytes, &format!("readback {i}")).unwrap())
            .collect();
        ctx.execute(|rec| {
            let out = renderer.record(rec, Slot::Main, Model::Ea, &second, &opts)?;
            rec.copy_image_to_buffer(out.image, 0, &readbacks[0]);
            let out = renderer.record(rec, Slot::Main, Model::Refract, &first, &opts)?;
            rec.copy_image_to_buffer(out.image, 0, &readbacks[1]);
            let out = renderer.record(rec, Slot::Main, Model::Refract, &second, &opts)?;
            rec.copy_image_to_buffer(out.image, 0, &readbacks[2]);
            Ok(())
        })
        .unwrap();
        for (buf, expected, what) in [
            (&readbacks[0], &expected_ea, "EA frame"),
            (&readbacks[1], &expected_first, "first sweep frame"),
            (&readbacks[2], &expected_second, "second sweep frame"),
        ] {
            let got: Vec<[f32; 4]> = buf.read_values(24 * 20).unwrap();
            assert_eq!(&got, &expected.pixels, "{what} differs from its render");
        }
    });
}

/// An Xvfb this test started; killed (and reaped) on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The display to use: $DISPLAY, else a fresh Xvfb. None (after a skip line) when there
/// is neither and REFRAKT_REQUIRE_DISPLAY is not 1.
fn display() -> Option<(String, Option<Xvfb>)> {
    if let Ok(d) = std::env::var("DISPLAY") {
        if !d.is_empty() {
            return Some((d, None));
        }
    }
    let spawned = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1024x768x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn();
    let mut child = match spawned {
        Ok(c) => c,
        Err(e) => {
            let required = std::env::var("REFRAKT_REQUIRE_DISPLAY").as_deref() == Ok("1");
            assert!(
                !required,
                "REFRAKT_REQUIRE_DISPLAY=1 but Xvfb cannot be started ({e}); install it \
                 (Debian package xvfb) with scripts/setup.sh"
            );
            println!(
                "skipped: no DISPLAY and no Xvfb ({e}); install xvfb (scripts/setup.sh) to \
                 test the viewer"
            );
            return None;
        }
    };
    // Xvfb writes the display number it chose once it accepts connections.
    let mut line = String::new();
    let stdout = child.stdout.take().expect("piped");
    BufReader::new(stdout)
        .read_line(&mut line)
        .expect("reading Xvfb's display number");
    let n: u32 = line
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("Xvfb printed '{line}' instead of a display number"));
    let display = format!(":{n}");
    Some((
        display.clone(),
        Some(Xvfb {
            child,
            display: display.clone(),
        }),
    ))
}

fn refrakt(args: &[&str], display: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_refrakt"))
        .args(args)
        .env("REFRAKT_VALIDATE", "1")
        .env("DISPLAY", display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("running refrakt")
}

fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8();
    (img.width(), img.height(), img.into_raw())
}

/// `render` the glass-floor scene with `scene` and `extra` at `size` into `headless`, and
/// check that the viewer's screenshot `shot` has that size and equals it within 1/255.
fn assert_shows_the_render(
    display: &str,
    scene: &[&str],
    extra: &[&str],
    shot: &Path,
    headless: &Path,
    size: (u32, u32),
) {
    let (width, height) = (size.0.to_string(), size.1.to_string());
    let mut args = vec![
        "render",
        "--scene",
        "glass-floor",
        "--width",
        &width,
        "--height",
        &height,
        "-o",
        headless.to_str().unwrap(),
    ];
    args.extend(scene);
    args.extend(extra);
    let o = refrakt(&args, display);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (w, h, shown) = read_png(shot);
    assert_eq!((w, h), size, "the screenshot has the window's size");
    let (_, _, expected) = read_png(headless);
    let (d, at) = max_difference(&shown, &expected);
    assert!(
        d <= 1,
        "viewer and render differ by {d}/255 at pixel ({}, {}) channel {}: {} vs {}",
        (at / 4) as u32 % w,
        (at / 4) as u32 / w,
        at % 4,
        shown[at],
        expected[at]
    );
}

#[test]
fn viewer_runs_resizes_and_shows_the_headless_image() {
    let _one = exclusive();
    let Some((display, xvfb)) = display() else {
        return;
    };
    if let Some(x) = &xvfb {
        println!("started Xvfb on {}", x.display);
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("view.png");
    let headless = dir.path().join("headless.png");
    // A refractive scene (glass sphere over a floor, the sky behind): sweep, caustic,
    // environment and tone mapping all show up in the comparison.
    let scene = [
        "--volume-size",
        "32",
        "--azimuth",
        "40",
        "--elevation",
        "25",
    ];
    let mut args = vec![
        "view",
        "glass-floor",
        "--width",
        "96",
        "--height",
        "64",
        "--frames",
        "5",
        "--resize",
        "120x80@2",
        "--screenshot",
        shot.to_str().unwrap(),
        "--no-axes",
        "--no-panel",
    ];
    args.extend(scene);
    let o = refrakt(&args, &display);
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{out}{err}");
    assert!(
        o.status.success(),
        "view failed ({}; 3 = validation messages):\n{err}",
        o.status
    );
    assert!(!err.contains("validation"), "{err}");
    assert!(out.contains("swapchain"), "{out}");
    for n in 0..5 {
        assert!(
            out.contains(&format!("frame {n}: ")),
            "frame {n} missing:\n{out}"
        );
    }
    assert!(
        out.contains("ms GPU, sweep") && out.contains("planes"),
        "{out}"
    );

    assert_shows_the_render(&display, &scene, &[], &shot, &headless, (120, 80));
    assert!(
        dir.path().join("view.exr").is_file(),
        "the linear EXR of the screenshot"
    );
    drop(xvfb);
}

/// "frame N: QUALITY: MS ms GPU, ..." lines of the viewer's log: (N, quality, ms).
fn frame_lines(out: &str) -> Vec<(u64, String, f64)> {
    out.lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("frame ")?;
            let (n, rest) = rest.split_once(": ")?;
            let (quality, rest) = rest.rsplit_once(": ")?;
            let ms = rest.split_once(" ms GPU")?.0.parse().ok()?;
            Some((n.parse().ok()?, quality.to_string(), ms))
        })
        .collect()
}

/// A preview's work from the viewer's description of it, "preview WxH, sample distance
/// xF": pixels times planes, up to a constant (the planes shrink with the factor F).
fn preview_work(quality: &str) -> f64 {
    let parse = || -> Option<f64> {
        let rest = quality.strip_prefix("preview ")?;
        let (size, factor) = rest.split_once(", sample distance x")?;
        let (w, h) = size.split_once('x')?;
        let [w, h, f]: [f64; 3] = [w.parse().ok()?, h.parse().ok()?, factor.parse().ok()?];
        Some(w * h / f)
    };
    parse().unwrap_or_else(|| panic!("not a preview's description: '{quality}'"))
}

#[test]
fn previews_while_dragging_fit_the_budget_and_the_refined_frame_is_the_render() {
    let _one = exclusive();
    // Issue 36: a scripted drag (the camera orbits 4 degrees before each of the first six
    // frames, as a mouse drag does) on a 256² window. Every frame while the view changes
    // is a preview whose GPU time (the viewer's own log) is within the budget; once the
    // view is still, the frame is full quality and equals `render` of the view the drag
    // ended at. Without previews the frames take seconds each on lavapipe; a refined frame
    // that kept a preview's size or sample distance would differ from the render.
    // The full frame renders in batches of planes: the scripted interruption turns the
    // camera once more after the first refinement's second batch, which must abandon that
    // frame there (and the last frame shows the view after the interruption).
    let Some((display, xvfb)) = display() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("refined.png");
    let headless = dir.path().join("headless.png");
    const BUDGET_MS: f64 = 100.0;
    let scene = [
        "--volume-size",
        "32",
        "--elevation",
        "25",
        "--light",
        "0,1,0",
        "--sample-distance",
        "2",
    ];
    let mut args = vec![
        "view",
        "glass-floor",
        "--width",
        "256",
        "--height",
        "256",
        "--azimuth",
        "40",
        "--drag",
        "6",
        "--frames",
        "9",
        "--preview-budget",
        "100",
        "--interrupt-refinement",
        "2",
        "--no-axes",
        "--no-panel",
        "--screenshot",
        shot.to_str().unwrap(),
    ];
    args.extend(scene);
    let o = refrakt(&args, &display);
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{out}{err}");
    assert!(o.status.success(), "view failed ({}):\n{err}", o.status);
    let frames = frame_lines(&out);
    let mut drag = Vec::new();
    for n in 0..6 {
        let (_, quality, ms) = frames
            .iter()
            .find(|f| f.0 == n)
            .unwrap_or_else(|| panic!("frame {n} missing:\n{out}"));
        assert!(
            quality.starts_with("preview "),
            "frame {n}, while dragging, is '{quality}'"
        );
        drag.push((quality.as_str(), *ms));
    }
    // The budget is met by a controller that learns from the frames' own times, and on
    // a shared 2-core machine a frame's time swings by a quarter from one frame to the
    // next (CI measured the same preview at 98–110 ms). So: on average within the budget;
    // none more than a third over it (the next dearer rung costs about twice as much:
    // four times the pixels or twice the planes; a full frame here about 19 times); and a
    // preview over the budget is answered by a cheaper one as soon as the frames already
    // in flight when its time came back (FRAMES_IN_FLIGHT = 2) are shown.
    let mean = drag.iter().map(|d| d.1).sum::<f64>() / drag.len() as f64;
    assert!(
        mean <= BUDGET_MS,
        "the drag's previews took {mean:.1} ms on average, over the {BUDGET_MS} ms budget:\n{out}"
    );
    let previews: Vec<_> = frames
        .iter()
        .filter(|f| f.1.starts_with("preview "))
        .collect();
    for (i, (n, quality, ms)) in previews.iter().enumerate() {
        assert!(
            *ms <= 4.0 / 3.0 * BUDGET_MS,
            "frame {n} ({quality}) took {ms} ms, a third over the {BUDGET_MS} ms budget"
        );
        let answer = previews.get(i + 3);
        if *ms > BUDGET_MS && answer.is_some() {
            let cheaper = previews[i + 1..=i + 3]
                .iter()
                .any(|later| preview_work(&later.1) < preview_work(quality));
            assert!(
                cheaper,
                "frame {n} ({quality}) took {ms} ms, over the budget, and the next three \
                 previews are no cheaper:\n{out}"
            );
        }
    }
    let last = frames.iter().find(|f| f.0 == 8).expect("frame 8");
    assert_eq!(last.1, "full", "the last frame is refined");
    assert!(
        last.2 > BUDGET_MS,
        "the full frame ({} ms) must cost more than a preview may, or the test shows nothing",
        last.2
    );

    // The refinement under way when the camera moved was abandoned after its second
    // batch, before its last plane.
    let abandoned = out
        .lines()
        .find_map(|l| {
            let rest = l.strip_prefix("refinement abandoned after ")?;
            let mut words = rest.split_whitespace();
            let done: u32 = words.next()?.parse().ok()?;
            let of: u32 = words.nth(1)?.parse().ok()?;
            Some((done, of))
        })
        .unwrap_or_else(|| panic!("no refinement was abandoned:\n{out}"));
    assert!(
        abandoned.0 >= 2 && abandoned.0 < abandoned.1,
        "abandoned after {} of {} planes",
        abandoned.0,
        abandoned.1
    );

    // The drag turned the camera from azimuth 40 by 6 × 4 degrees, the interruption by 4
    // more.
    assert_shows_the_render(
        &display,
        &scene,
        &["--azimuth", "12"],
        &shot,
        &headless,
        (256, 256),
    );
    drop(xvfb);
}

#[test]
fn view_options_and_a_missing_display_are_clear_errors() {
    let _one = exclusive();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_refrakt"))
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("running refrakt")
    };
    for (args, needle) in [
        (
            &["view", "--resize", "12@3", "--volume-size", "8"][..],
            "expected WIDTHxHEIGHT@FRAME",
        ),
        (
            &["view", "--frames", "0", "--volume-size", "8"][..],
            "at least 1",
        ),
        (&["view", "--screenshot", "x.png"][..], "--frames"),
        (
            &["view", "--preview-budget", "-5", "--volume-size", "8"][..],
            "--preview-budget -5: expected a frame time in ms",
        ),
        (
            &["view", "--interrupt-refinement", "0", "--volume-size", "8"][..],
            "--interrupt-refinement must be at least 1",
        ),
        (
            &[
                "view",
                "--interrupt-refinement",
                "2",
                "--preview-budget",
                "0",
                "--volume-size",
                "8",
            ][..],
            "--interrupt-refinement needs previews",
        ),
        (
            &["view", "sphere", "--scene", "box"][..],
            "cannot be used with",
        ),
        (
            &["view", "sphere", "--volume-size", "8"][..],
            "no display (DISPLAY and WAYLAND_DISPLAY unset)",
        ),
    ] {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        assert!(err.contains(needle), "{args:?}: no '{needle}' in: {err}");
        // One line, and no source path of a dependency (issue 15).
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!err.contains(".cargo") && !err.contains(".rs:"), "{err}");
    }
}

#[test]
fn the_panel_opens_with_a_click_and_switches_the_environment_and_the_clipping_plane() {
    let _one = exclusive();
    // Issue 36: the on-screen panel (egui) is folded into a title bar in the top-left
    // corner at first; a click on it opens it, a choice of "none" in its environment box
    // puts the background colour behind the volume, and a click on its "clipping plane"
    // box turns the clipping plane on, which the viewer says on stdout as the C key does.
    // Real pointer input through the X server (xdotool), validation on. With the panel
    // not drawn, not placed where it is laid out, or not wired to the view, no "clipping
    // on" line comes.
    let Some((display, xvfb)) = display() else {
        return;
    };
    if Command::new("xdotool").arg("version").output().is_err() {
        assert!(
            std::env::var("REFRAKT_REQUIRE_DISPLAY").as_deref() != Ok("1"),
            "REFRAKT_REQUIRE_DISPLAY=1 but xdotool is missing (scripts/setup.sh installs it)"
        );
        println!("skipped: no xdotool (scripts/setup.sh installs it)");
        return;
    }
    // Drawn: a screenshot (as shown) has the folded panel's dark title bar in the
    // top-left corner over the render, and is the render everywhere below it.
    let dir = tempfile::tempdir().unwrap();
    let (shot, headless) = (dir.path().join("panel.png"), dir.path().join("render.png"));
    let scene = ["--volume-size", "32", "--sample-distance", "2", "--no-axes"];
    let size = ["--width", "160", "--height", "120"];
    let mut args = vec!["view", "glass-floor", "--frames", "1", "--screenshot"];
    args.push(shot.to_str().unwrap());
    args.extend(scene.iter().chain(&size));
    let o = refrakt(&args, &display);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut args = vec!["render", "--scene", "glass-floor", "-o"];
    args.push(headless.to_str().unwrap());
    args.extend(scene.iter().chain(&size).filter(|a| **a != "--no-axes"));
    let o = refrakt(&args, &display);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ((w, _, shown), (_, _, rendered)) = (read_png(&shot), read_png(&headless));
    let (mut bar, mut below) = (0, 0u8);
    for (i, (a, b)) in shown.chunks(4).zip(rendered.chunks(4)).enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap();
        if x < 150 && y < 30 && d > 32 {
            bar += 1;
        } else if y >= 40 {
            below = below.max(d);
        }
    }
    println!("title bar: {bar} pixels differ by more than 32/255; below it max {below}/255");
    assert!(bar > 2000, "no panel drawn over the frame ({bar} pixels)");
    assert!(
        below <= 1,
        "the frame below the panel differs by {below}/255"
    );

    let xdotool = |args: &[&str]| {
        let o = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &display)
            .output()
            .expect("running xdotool");
        String::from_utf8_lossy(&o.stdout).trim().to_string()
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_refrakt"))
        .args([
            "view",
            "glass-floor",
            "--volume-size",
            "32",
            "--width",
            "400",
            "--height",
            "400",
            "--sample-distance",
            "2",
        ])
        .current_dir(dir.path())
        .env("REFRAKT_VALIDATE", "1")
        .env("DISPLAY", &display)
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting refrakt view");
    let (tx, rx) = std::sync::mpsc::channel();
    let stdout = child.stdout.take().expect("piped");
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut log = String::new();
    let mut wait_for = |needle: &str, secs: u64| -> bool {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(secs);
        while let Some(left) = deadline.checked_duration_since(std::time::Instant::now()) {
            match rx.recv_timeout(left) {
                Ok(line) => {
                    log.push_str(&line);
                    log.push('\n');
                    if line.contains(needle) {
                        return true;
                    }
                }
                Err(_) => return false,
            }
        }
        false
    };
    let shown = wait_for("frame 0: ", 120);
    let window = xdotool(&["search", "--sync", "--name", "refrakt view"]);
    let window = window.lines().next().unwrap_or_default().to_string();
    let (mut clicked, mut env_set, mut shot_taken) = (false, false, false);
    if shown && !window.is_empty() {
        let click = |x: &str, y: &str| {
            xdotool(&["mousemove", "--window", &window, x, y, "click", "1"]);
            std::thread::sleep(std::time::Duration::from_millis(1500));
        };
        // The folded panel's title bar, then (once open) its "environment" combo box and
        // in the list it opens (upwards, the window's bottom being near) "none", whose
        // background colour then lies behind the glass instead of the scene's sky; then
        // the "clipping plane" box.
        click("16", "17");
        click("60", "330");
        click("60", "307");
        env_set = wait_for("environment: none", 30);
        xdotool(&["windowfocus", "--sync", &window]);
        xdotool(&["key", "p"]);
        shot_taken = wait_for("screenshot: ", 120);
        click("14", "301");
        clicked = wait_for("clipping on", 30);
    }
    let _ = child.kill();
    let out = child.wait_with_output().expect("refrakt view");
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{log}{err}");
    assert!(shown, "the viewer showed no frame:\n{log}{err}");
    assert!(!window.is_empty(), "no window named 'refrakt view'");
    assert!(env_set, "the panel did not switch the environment:\n{log}");
    assert!(
        shot_taken,
        "no screenshot after the environment switch:\n{log}"
    );
    // The frame's top-right corner, beside the panel: the sky there before (light grey
    // and white checks, 198/255 at most when the choice does not reach the renderer), the
    // dark background colour (0.08, 0.08, 0.1 linear: 99/255 at most) after.
    let (w, _, pixels) = read_png(&dir.path().join("refrakt-glass-floor-001.png"));
    let corner: Vec<u8> = (370..390)
        .flat_map(|x| (10..30).map(move |y| (x, y)))
        .map(|(x, y)| {
            pixels[((y * w + x) * 4) as usize..][..3]
                .iter()
                .copied()
                .max()
                .unwrap()
        })
        .collect();
    let brightest = corner.iter().copied().max().unwrap();
    println!("environment none: the corner beside the panel at most {brightest}/255");
    assert!(
        brightest < 150,
        "the background colour is not behind the volume after choosing no environment: \
         the corner beside the panel reaches {brightest}/255"
    );
    assert!(clicked, "the panel did not turn clipping on:\n{log}");
    assert!(!err.contains("[vulkan"), "validation messages:\n{err}");
    drop(xvfb);
}

//! Shared test helpers: a validated lavapipe context and a check that the validation layer
//! stayed silent for the whole life of the context (creation to destruction).
#![allow(dead_code)]

use std::sync::Arc;

pub mod floor;

use refrakt::render::{Camera, Frame, Light, Model, RenderOptions, Renderer};
use refrakt::transfer::TransferFunctions;
use refrakt::vk::{Context, ContextDesc, ValidationLog};
use refrakt::volume::{Volume, Voxels};

/// One validated context at a time in a test process. CI once died in the preintegration
/// tests with glibc's "malloc_consolidate(): unaligned fastbin chunk detected" (SIGABRT,
/// stop 39; 258 tests had passed the run before with the same code): heap corruption
/// while several tests drove their own instance, device and validation layer from parallel
/// threads. Debian's 1.3.239 validation layer and loader keep process-wide state (the
/// layer's per-dispatch-key maps, its state tracker's allocator) whose thread safety
/// across instances has had races fixed upstream; our own code holds no state shared
/// between contexts. So a test holds this lock for its context's whole life. lavapipe
/// still uses every core inside each submit; the CPU-only parts of tests still overlap.
static CONTEXT_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A validated context that holds [`CONTEXT_LOCK`] until it is dropped (after the context:
/// fields drop in declaration order). Derefs to the context.
pub struct TestContext {
    ctx: Context,
    _lock: std::sync::MutexGuard<'static, ()>,
}

impl std::ops::Deref for TestContext {
    type Target = Context;
    fn deref(&self) -> &Context {
        &self.ctx
    }
}

/// A context with validation and synchronization validation on. Honours REFRAKT_DEVICE so
/// the suite can be pointed at a real GPU. Holds the process's context lock (a test that
/// panicked with it poisons nothing: the next test takes it anyway).
pub fn context() -> TestContext {
    context_with(ContextDesc::default())
}

/// [`context`] from `desc` (its validation and device are the tests').
pub fn context_with(desc: ContextDesc) -> TestContext {
    let lock = CONTEXT_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = Context::new(&ContextDesc {
        validate: true,
        device: std::env::var("REFRAKT_DEVICE")
            .ok()
            .filter(|d| !d.is_empty()),
        ..desc
    })
    .expect("creating a validated Vulkan context (is scripts/setup.sh run?)");
    TestContext { ctx, _lock: lock }
}

/// Panics with every message if the layer reported anything. Call after dropping the
/// context and everything made from it.
pub fn assert_no_validation_messages(log: &Arc<ValidationLog>) {
    let msgs = log.messages();
    assert!(
        msgs.is_empty(),
        "{} validation message(s):\n{}",
        msgs.len(),
        msgs.join("\n---\n")
    );
}

/// Run `f` with a validated context and fail on any validation message.
pub fn with_context<R>(f: impl FnOnce(&Context) -> R) -> R {
    with_context_from(ContextDesc::default(), f)
}

/// [`with_context`] on a context made from `desc` ([`context_with`]).
pub fn with_context_from<R>(desc: ContextDesc, f: impl FnOnce(&Context) -> R) -> R {
    let ctx = context_with(desc);
    let log = ctx.validation_log();
    let r = f(&ctx);
    drop(ctx);
    assert_no_validation_messages(&log);
    r
}

/// Camera on the +z axis looking down -z at the volume centre.
pub fn face_on(distance: f32, fov_y: f32) -> Camera {
    Camera {
        azimuth: 0.0,
        elevation: 0.0,
        distance,
        fov_y,
        ..Default::default()
    }
}

pub fn render(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunctions,
    camera: &Camera,
    opts: &RenderOptions,
) -> Frame {
    let mut r = Renderer::new(ctx, volume, tf).expect("renderer");
    r.render(Model::Ea, camera, opts).expect("render")
}

/// A TF with constant colour and opacity everywhere.
pub fn constant_tf(colour: [f32; 3], opacity: f32) -> TransferFunctions {
    let text = format!(
        "colour = [[0.0, {}, {}, {}]]\nopacity = [[0.0, {opacity}]]\n",
        colour[0], colour[1], colour[2]
    );
    TransferFunctions::parse(&text, "test tf").unwrap()
}

/// The `refrakt` binary with validation on (REFRAKT_VALIDATE=1: exit status 3 on any
/// validation message), ready for arguments.
pub fn refrakt_command(args: &[&str]) -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_refrakt"));
    c.args(args).env("REFRAKT_VALIDATE", "1");
    c
}

/// Runs `refrakt` with validation on and returns its output.
pub fn refrakt(args: &[&str]) -> std::process::Output {
    refrakt_command(args).output().expect("running refrakt")
}

/// An n³ volume of f32 values f(p), p the voxel centre in [-0.5, 0.5]³, clamped to [0, 1]
/// and mapped to [0, 1] unchanged.
/// A value's profile across a face of glass, `x` voxels inside it (negative: outside):
/// the one-voxel linear ramp 0.5 + x (the transfer functions clamp it to 0..1), or with
/// `ramp` a tanh whose 10-90 % rise spans `ramp` voxels (tanh reaches ±0.8 at
/// ±atanh(0.8) = ±1.0986 of its widths).
pub fn face_profile(x: f32, ramp: Option<f32>) -> f32 {
    match ramp {
        Some(r) => 0.5 + 0.5 * (x * 2.0 * 1.0986 / r).tanh(),
        None => 0.5 + x,
    }
}

/// The glass wedge of the total-reflection tests, n³ voxels: glass (value 1) below the
/// entry face z = 0.45 and inside the exit face, whose outward normal (sin a, 0, -cos a)
/// makes `angle` degrees with -z (the face-on camera's view, the headlight's travel),
/// through (0, 0, -0.1); the faces meet outside the box. Faces as `face_profile` says.
pub fn glass_wedge(n: u32, angle: f32, ramp: Option<f32>) -> Volume {
    let a = angle.to_radians();
    let m = glam::Vec3::new(a.sin(), 0.0, -a.cos());
    f32_volume(n, |p| {
        let p = glam::Vec3::from(p);
        let entry = 0.45 - p.z;
        let exit = -(p - glam::Vec3::new(0.0, 0.0, -0.1)).dot(m);
        face_profile(entry.min(exit) * n as f32, ramp)
    })
}

pub fn f32_volume(n: u32, f: impl Fn([f32; 3]) -> f32) -> Volume {
    let mut v = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z].map(|i| (i as f32 + 0.5) / n as f32 - 0.5);
                v.push(f(p).clamp(0.0, 1.0));
            }
        }
    }
    let mut vol = Volume::new([n; 3], [1.0; 3], Voxels::F32(v)).unwrap();
    vol.range = Some((0.0, 1.0));
    vol
}

/// Value 1 inside a ball of radius r centred at `c`, 0 outside, a one-voxel linear ramp
/// on the surface.
pub fn ball_at(n: u32, r: f32, c: [f32; 3]) -> Volume {
    f32_volume(n, |p| {
        0.5 + (r - (glam::Vec3::from(p) - glam::Vec3::from(c)).length()) * n as f32
    })
}

/// [`ball_at`] the centre.
pub fn ball(n: u32, r: f32) -> Volume {
    ball_at(n, r, [0.0; 3])
}

/// A glass ball (η 1.6, radius 0.3 of the box, a one-voxel ramp; 48³) in the procedural
/// checkered sky, seen from 20° round and 10° up through a 35° field: behind it the rays
/// of neighbouring pixels leave in very different directions, so one environment lookup
/// per pixel aliases (the environment-footprint tests of the sweep and the eikonal view).
pub fn glass_ball_in_the_sky() -> (
    Volume,
    TransferFunctions,
    refrakt::environment::EnvironmentMap,
    Camera,
) {
    let tf = TransferFunctions {
        eta: refrakt::transfer::Piecewise::new(vec![(0.0, [1.0]), (1.0, [1.6])]),
        ..Default::default()
    };
    let camera = Camera {
        azimuth: 20.0,
        elevation: 10.0,
        distance: 2.2,
        fov_y: 35.0,
        ..Default::default()
    };
    let map = refrakt::environment::EnvironmentMap::procedural(512).unwrap();
    (ball(48, 0.3), tf, map, camera)
}

/// A slab of clear glass (η 1.5) across the box at |z| < 0.25 with one-voxel faces (value
/// 0.4), and with `block` = (top, front) an opaque blue block in front of it (value 1:
/// y < top, z > front): the Fresnel tests of the eikonal view and the sweep, whose
/// viewing ray from 45° above through the centre passes above the block and whose
/// reflection at the slab's front face runs into it.
pub fn glass_slab(n: u32, block: Option<(f32, f32)>) -> (Volume, TransferFunctions) {
    use refrakt::transfer::Piecewise;
    let nf = n as f32;
    let volume = f32_volume(n, |p| match block {
        Some((top, front)) if p[1] < top && p[2] > front => 1.0,
        _ => 0.4 * ((0.25 - p[2].abs()) * nf + 0.5).clamp(0.0, 1.0),
    });
    let tf = TransferFunctions {
        colour: Piecewise::new(vec![
            (0.0, [0.0; 3]),
            (0.6, [0.0; 3]),
            (0.7, [0.0, 0.0, 1.0]),
        ]),
        opacity: Piecewise::new(vec![(0.0, [0.0]), (0.6, [0.0]), (0.7, [1.0])]),
        eta: Piecewise::new(vec![(0.0, [1.0]), (0.4, [1.5]), (0.5, [1.5]), (0.6, [1.0])]),
        ..Default::default()
    };
    (volume, tf)
}

/// An environment red where a direction points to +z (the camera's side of the slab of
/// [`glass_slab`]) and green where it points to -z.
pub fn red_towards_camera_green_beyond() -> refrakt::environment::EnvironmentMap {
    environment_from(256, |d| {
        if d.z > 0.0 {
            [1.0, 0.0, 0.0, 1.0]
        } else {
            [0.0, 1.0, 0.0, 1.0]
        }
    })
}

/// One frame of the refractive plane sweep.
pub fn sweep(
    ctx: &Context,
    vol: &Volume,
    tf: &TransferFunctions,
    cam: &Camera,
    opts: &RenderOptions,
) -> Frame {
    let mut r = Renderer::new(ctx, vol, tf).expect("renderer");
    r.render(Model::Refract, cam, opts).expect("render")
}

/// Light along the view axis (travelling away from the camera), white.
pub fn headlight(cam: &Camera, softness: f32) -> Light {
    Light {
        source: refrakt::light::LightSource::Directional {
            towards: (cam.eye() - cam.target).normalize(),
        },
        colour: [1.0; 3],
        softness,
    }
}

/// Clear glass: eta rising linearly from 1 at value 0 to `eta` at value 1, nothing else.
pub fn glass(eta: f32) -> TransferFunctions {
    TransferFunctions {
        eta: refrakt::transfer::Piecewise::new(vec![(0.0, [1.0]), (1.0, [eta])]),
        ..Default::default()
    }
}

/// Render options of a `width` × `height` frame at sample distance `sd`, the rest default.
pub fn frame_options(width: u32, height: u32, sd: f32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        sample_distance: sd,
        ..Default::default()
    }
}

/// An equirectangular environment map `width` × `width / 2` whose radiance in world
/// direction d is `radiance(d)` (at texel centres).
pub fn environment_from(
    width: u32,
    radiance: impl Fn(glam::Vec3) -> [f32; 4],
) -> refrakt::environment::EnvironmentMap {
    use refrakt::environment::{direction, pixel_angles, EnvironmentMap};
    let height = width / 2;
    let mut px = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let (phi, theta) = pixel_angles(width, height, x as f32 + 0.5, y as f32 + 0.5);
            px.push(radiance(glam::Vec3::from(direction(phi, theta))));
        }
    }
    EnvironmentMap::new(width, height, px, "test map").unwrap()
}

/// L / (light colour · albedo · colour) along the ray through the centre of the cube
/// [-h, h]³ from +z (direction -z), light from `towards` (unit, x = 0, y ≥ 0; z < 0 is a
/// light in front of the camera), extinction `k` per world unit, phase 4π·p_HG(cos θ; g):
/// ∫₀^{2h} k e^{-k t} T_light(t) dt with T_light = e^{-k ℓ(t)}, ℓ the distance from
/// (0, 0, h − t) along `towards` to the cube's face.
pub fn single_scattering_block(k: f64, h: f64, towards: [f64; 3], g: f64) -> f64 {
    let exit = |t: f64| -> f64 {
        let mut l = f64::INFINITY;
        if towards[1] > 0.0 {
            l = l.min(h / towards[1]);
        }
        if towards[2] > 0.0 {
            l = l.min(t / towards[2]);
        }
        if towards[2] < 0.0 {
            l = l.min((2.0 * h - t) / -towards[2]);
        }
        l
    };
    let n = 200_000;
    let dt = 2.0 * h / n as f64;
    let integral: f64 = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) * dt;
            k * (-k * t).exp() * (-k * exit(t)).exp() * dt
        })
        .sum();
    let cos = -towards[2]; // towards · (0, 0, -1)
    let d = 1.0 + g * g - 2.0 * g * cos;
    integral * (1.0 - g * g) / (d * d.sqrt())
}

/// Largest and mean difference of two frames' display values (tone mapped, sRGB, 8 bit as
/// the PNG writer makes them), colour channels, as fractions of the display range.
pub struct DisplayDiff {
    pub max: f32,
    pub mean: f32,
}

pub fn display_diff(a: &Frame, b: &Frame, tone: &refrakt::tone::ToneMap) -> DisplayDiff {
    let (a, b) = (
        refrakt::output::to_srgb8(a, tone),
        refrakt::output::to_srgb8(b, tone),
    );
    let (mut max, mut sum, mut n) = (0.0f32, 0.0f64, 0usize);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        if k % 4 == 3 {
            continue;
        }
        let d = (*x as f32 - *y as f32).abs() / 255.0;
        max = max.max(d);
        sum += d as f64;
        n += 1;
    }
    DisplayDiff {
        max,
        mean: (sum / n as f64) as f32,
    }
}

/// Largest difference of any linear RGBA value, relative to the value where it exceeds 1
/// (HDR light: float rounding of differently compiled code scales with it).
pub fn linear_max(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs() / p[c].abs().max(1.0)))
        .fold(0.0, f32::max)
}

/// Over (row, mean) points: the RMS of the differences between consecutive rows after a
/// least-squares quadratic trend over the rows is removed, relative to the mean level;
/// the level; the largest such difference relative to the level.
pub fn detrended_row_to_row(rows: &[(f64, f64)]) -> (f64, f64, f64) {
    let (mut m, mut rhs) = (glam::DMat3::ZERO, glam::DVec3::ZERO);
    for &(x, v) in rows {
        let b = glam::DVec3::new(1.0, x, x * x);
        m += glam::DMat3::from_cols(b * b.x, b * b.y, b * b.z);
        rhs += b * v;
    }
    let c = m.inverse() * rhs;
    let level = rows.iter().map(|p| p.1).sum::<f64>() / rows.len() as f64;
    let res: Vec<f64> = rows
        .iter()
        .map(|&(x, v)| v - (c.x + c.y * x + c.z * x * x))
        .collect();
    let d: Vec<f64> = res.windows(2).map(|p| p[1] - p[0]).collect();
    let rms = (d.iter().map(|d| d * d).sum::<f64>() / d.len() as f64).sqrt();
    let max = d.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    (rms / level, level, max / level)
}

/// Row means of channel 0 over the central half of the columns, for the rows whose every
/// such pixel is opaque (alpha > 0.99: a floor filling them); at least 40 such rows.
pub fn floor_rows(f: &Frame) -> Vec<(f64, f64)> {
    let (w, h) = (f.width, f.height);
    let mut rows = Vec::new();
    for y in 0..h {
        let (mut s, mut c) = (0.0f64, 0);
        for x in w / 4..3 * w / 4 {
            let p = f.pixel(x, y);
            if p[3] > 0.99 {
                s += p[0] as f64;
                c += 1;
            }
        }
        if c == w / 2 {
            rows.push((y as f64, s / c as f64));
        }
    }
    assert!(rows.len() > 40, "too few floor rows ({})", rows.len());
    rows
}

/// Channel 0 of a `w` × `h` image box-filtered 3 × 3 (the border left at 0).
pub fn smoothed(img: &[[f32; 4]], w: usize, h: usize) -> Vec<f64> {
    let mut out = vec![0.0; w * h];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let mut s = 0.0;
            for dy in 0..3 {
                for dx in 0..3 {
                    s += img[(y + dy - 1) * w + x + dx - 1][0] as f64;
                }
            }
            out[y * w + x] = s / 9.0;
        }
    }
    out
}

/// The linear RGB pixels of an EXR written by `render`, row-major from the top, with the
/// image's width.
pub fn read_exr_rgb(path: &std::path::Path) -> (usize, Vec<[f32; 3]>) {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b];
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data.channel_data.pixels
}

/// A renderer of `scene`'s volume, transfer functions and environment.
pub fn renderer_for(ctx: &Context, scene: &refrakt::scene::Scene) -> Renderer {
    let volume = scene.load_volume(&std::env::temp_dir(), None).unwrap();
    let tf = scene.transfer_functions().unwrap();
    let mut renderer = Renderer::new(ctx, &volume, &tf).unwrap();
    renderer
        .set_environment(scene.environment_map().unwrap().as_ref())
        .unwrap();
    renderer
}

/// The built-in glass sphere on its floor (a caustic, a shadow, Fresnel reflections, the
/// sky) with its environment, seen obliquely (35° round from the scene's camera, 40°
/// up): the scene, a renderer for it and the camera.
pub fn sphere_on_floor_oblique(ctx: &Context) -> (refrakt::scene::Scene, Renderer, Camera) {
    let scene = refrakt::scene::Scene::builtin("sphere-on-floor")
        .unwrap()
        .unwrap();
    let renderer = renderer_for(ctx, &scene);
    let cam = Camera {
        azimuth: scene.camera.azimuth + 35.0,
        elevation: 40.0,
        ..scene.camera
    };
    (scene, renderer, cam)
}

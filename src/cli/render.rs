//! `refrakt render`: one frame to an image, with the GPU time of every pass, the sweep's
//! statistics and optional state-buffer dumps.

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

use anyhow::{bail, ensure, Result};

use refrakt::output;
use refrakt::render::{
    upload, Camera, LightTransport, Model, Renderer, StateBuffer, SweepPath, MAX_LIGHT_RAYS,
};
use refrakt::scene::LoadedScene;
use refrakt::vk::{self, Context, ContextDesc};

use super::args::*;
use super::info::*;
use super::scene_args::*;

/// GPU time of a frame's rendering passes, without the one-off builds (preintegration
/// table, environment SAT) that happen only when their inputs change.
pub fn main_pass_ms(frame: &refrakt::render::Frame) -> f64 {
    frame.timings.get("render").unwrap_or(0.0)
}

/// A spinner with `message` and the elapsed time on stderr, drawn only on a terminal.
fn spinner(message: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new_spinner();
    if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
        pb.set_style(style);
    }
    pb.set_message(message.to_owned());
    pb.enable_steady_tick(std::time::Duration::from_millis(200));
    pb
}

/// The fraction of a frame done and the time left, from the progress the GPU reports.
/// The rate comes from the marks passed so far, timed from the first one: the work before
/// it (one-off builds, the setup pass) is not part of the planes' rate.
#[derive(Default)]
struct Eta {
    first: Option<(std::time::Instant, f64)>,
}

impl Eta {
    fn update(&mut self, fraction: f64) -> String {
        let now = std::time::Instant::now();
        if fraction <= 0.0 {
            return "waiting for the first planes".into();
        }
        let (t0, f0) = *self.first.get_or_insert((now, fraction));
        let done = format!("{:.0} % of the planes", 100.0 * fraction);
        if fraction <= f0 || fraction >= 1.0 {
            return done;
        }
        let rate = (fraction - f0) / now.duration_since(t0).as_secs_f64();
        let left = (1.0 - fraction) / rate;
        format!("{done}, about {} left", human_seconds(left))
    }
}

/// `s` seconds as a person reads them: "8 s", "3 min 20 s".
fn human_seconds(s: f64) -> String {
    let s = s.round() as u64;
    if s < 60 {
        format!("{s} s")
    } else {
        format!("{} min {} s", s / 60, s % 60)
    }
}

/// Timestamp scopes of builds that are not part of a frame (see `Renderer`).
fn one_off(scope: &str) -> bool {
    refrakt::render::rebuild_scopes().contains(&scope)
        || refrakt::render::sat3d::AXIS_SCOPES.contains(&scope)
}

pub fn render(desc: &ContextDesc, args: &RenderArgs) -> Result<ExitCode> {
    if let Some(code) = list_and_exit(&args.scene)? {
        return Ok(code);
    }
    // Everything that can be checked without the GPU is checked first, so bad input fails
    // at once with a clear message.
    output::format_for(&args.output)?;
    // --variant and --pass-timings are the sweep's: refused with --model ea like
    // --softness and the rest.
    let mut flags = Vec::new();
    if args.variant.is_some() {
        flags.push("--variant");
    }
    if args.pass_timings {
        flags.push("--pass-timings");
    }
    if args.plane_flux {
        flags.push("--plane-flux");
    }
    let scene = scene_with_refract_only(&args.scene, &flags)?;
    let dumps = match &args.dump {
        Some(d) => parse_dumps(d)?,
        None => Vec::new(),
    };
    ensure!(
        args.dump_dir.is_none() || !dumps.is_empty(),
        "--dump-dir is where --dump writes its state buffers: give --dump too"
    );
    let dump_dir = match &args.dump_dir {
        Some(d) => d.clone(),
        None => args
            .output
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_default(),
    };
    if !dumps.is_empty() && !dump_dir.as_os_str().is_empty() && !dump_dir.is_dir() {
        bail!(
            "--dump-dir {}: {}",
            dump_dir.display(),
            if dump_dir.exists() {
                "is a file, not a folder"
            } else {
                "the folder does not exist"
            }
        );
    }
    // Every file this render writes, checked against every file it reads before any work
    // (issue 33): writable, not a folder, not an input, not each other.
    let data_dir = data_dir(&args.scene);
    let mut inputs = scene.input_files(&data_dir);
    inputs.extend(args.scene.ambient_table.clone());
    let dump_paths: Vec<_> = dumps
        .iter()
        .map(|&(buffer, plane)| dump_path(&dump_dir, buffer, plane))
        .collect();
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(dump_paths.iter().map(|p| ("--dump", p.as_path())));
    refrakt::files::check_outputs(&outputs, &inputs)?;
    // The device first: its limits let the loaders refuse a volume it cannot hold from
    // the file's header, before reading gigabytes.
    let ctx = Context::new(desc)?;
    println!(
        "device: {} ({})",
        ctx.info().name,
        vk::device_type_name(ctx.info().device_type)
    );
    // Loading, generating a stand-in and a big frame can take minutes: say which phase
    // is running (on a terminal only; indicatif draws nothing otherwise).
    let progress = spinner("loading the scene");
    let LoadedScene {
        name,
        volume,
        tf,
        env,
        model,
        camera,
        mut opts,
        tone,
        notes,
        ..
    } = scene.load_all(&data_dir, Some(upload::device_limits(&ctx)))?;
    progress.suspend(|| notes.iter().for_each(|n| println!("{n}")));
    opts.sweep.dumps = dumps;
    opts.sweep.pass_timings = args.pass_timings;
    ensure!(
        !args.plane_flux || opts.sweep.light_transport == LightTransport::Forward,
        "--plane-flux is the forward light transport's: the backward step's planes hold the \
         flux per unit plane area already, and the eikonal transport reads a light volume"
    );
    opts.sweep.plane_flux = args.plane_flux;
    if let Some(levers) = args.variant {
        opts.sweep.levers = levers;
        progress.suspend(|| println!("sweep variant: {levers}"));
    }

    progress.set_message(format!(
        "uploading the {}x{}x{} volume",
        volume.dims[0], volume.dims[1], volume.dims[2]
    ));
    let mut renderer = Renderer::new(&ctx, &volume, &tf)?;
    // Long one-off work (the eikonal light simulation, minutes on a CPU device) says how
    // far it is on the spinner's line.
    let bar = progress.clone();
    renderer.set_build_progress(Some(std::sync::Arc::new(move |line: &str| {
        bar.set_message(line.to_owned())
    })));
    if model == Model::Ambient {
        progress.set_message("the ambient-scattering table");
        let (table, line) = progress.suspend(|| {
            super::ambient::table_for(
                args.scene.ambient_table.as_deref(),
                refrakt::render::ScatterOptions::of(&opts).albedo,
                false,
            )
        })?;
        progress.suspend(|| println!("{line}"));
        renderer.set_ambient_table(&table)?;
    }
    let env_timings = if model.takes_flag("--env") {
        renderer.set_environment(env.as_ref())?
    } else {
        Default::default()
    };
    progress.set_message(format!(
        "rendering {}x{} with {} (one GPU submission; on lavapipe this can take minutes)",
        opts.width,
        opts.height,
        model.name()
    ));
    // On a terminal the frame reports how far the GPU is (timestamps every 2 % of the
    // planes, read while it runs); piped, nothing is drawn and the frame has no marks.
    let mut frame = if std::io::stderr().is_terminal() {
        let what = format!(
            "rendering {}x{} with {}",
            opts.width,
            opts.height,
            model.name()
        );
        let mut eta = Eta::default();
        renderer.render_observed(model, &camera, &opts, &mut |fraction| {
            progress.set_message(format!("{what}: {}", eta.update(fraction)));
        })?
    } else {
        renderer.render(model, &camera, &opts)?
    };
    progress.finish_and_clear();
    // One-off builds first (the gradient volume once per volume, the environment's SAT
    // once per map), then the frame's own passes.
    let mut all = renderer.gradient_timings().clone();
    all.extend(env_timings);
    all.extend(std::mem::take(&mut frame.timings));
    frame.timings = all;
    output::write(&frame, &args.output, &tone)?;
    println!(
        "rendered {}x{} of the {} scene ({}x{}x{}, transfer functions {}), model {}{}, sample distance {}, up to {} steps per ray",
        opts.width,
        opts.height,
        name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        model.name(),
        if opts.preintegrated { " (preintegrated)" } else { "" },
        opts.sample_distance,
        frame.max_steps
    );
    if let refrakt::render::gradient::GradientStatus::TooLarge { needed, budget } =
        renderer.gradient_status()
    {
        println!(
            "note: the gradient volume would need {} MiB (budget {} MiB, half the device's \
             largest heap): surface normals computed on the fly instead (3D Sobel, ~1.5° \
             less accurate at faces of glass; docs/NOTES.md)",
            needed >> 20,
            budget >> 20
        );
    }
    // The eikonal light simulation (the eikonal model, the sweep's eikonal transport):
    // how each light's wavefront grew and where its light went.
    for stats in renderer.light_simulation_stats(model).iter() {
        println!("light simulation, {}: {}", stats.label(), stats.summary());
    }
    if frame.timings.scopes.is_empty() {
        println!("GPU timings: this device has no timestamp queries");
    } else {
        // One-off builds are outside the frame: they run again only when their inputs
        // change (volume, transfer functions, environment map), not per frame.
        let scopes = &frame.timings.scopes;
        println!("GPU time of the one-off builds (again only when their inputs change):");
        for (name, ms) in scopes.iter().filter(|(n, _)| one_off(n)) {
            println!("  {name:<16} {ms:9.3} ms");
        }
        println!("GPU time of the frame, per pass:");
        // A pass timed per plane (--pass-timings) has one scope per plane: summed.
        let mut names: Vec<&str> = Vec::new();
        for (name, _) in scopes.iter().filter(|(n, _)| n != "render" && !one_off(n)) {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
        }
        for name in names {
            let ms = frame.timings.get(name).unwrap_or(0.0);
            println!("  {name:<24} {ms:9.3} ms");
        }
        if let Some(ms) = frame.timings.get("render") {
            println!(
                "  {:<24} {ms:9.3} ms (the frame's passes above and their barriers)",
                "frame"
            );
        }
    }
    if let Some(stats) = &frame.sweep {
        let planes = stats.planes.count;
        let per_plane = frame
            .timings
            .get("sweep")
            .map(|ms| format!(", {:.3} ms per plane", ms / planes as f64))
            .unwrap_or_default();
        println!(
            "sweep: {planes} planes as {}, spacing {:.5}{per_plane}",
            match stats.path {
                SweepPath::Compute => "compute dispatches",
                _ => "draws",
            },
            stats.planes.spacing,
        );
    }
    // Developer diagnostics (-v): what the sweep shaded and moved, its light-ray grid
    // and what it clamped.
    if let (Some(stats), true) = (&frame.sweep, args.verbose) {
        println!(
            "sweep state: {:.0} % of the viewport shaded per plane (mean), {:.1} MiB of \
             state-buffer traffic per plane ({:.1} MiB compulsory: each state texel read \
             and written once)",
            100.0 * stats.shaded_fraction,
            stats.bytes_per_plane as f64 / (1 << 20) as f64,
            stats.compulsory_bytes_per_plane as f64 / (1 << 20) as f64
        );
        if stats.light_transport == LightTransport::Forward {
            let [columns, rows, ..] = stats.light_rays;
            let [asked, launched] = stats.light_spacing;
            print!(
                "light rays: {columns} × {rows}, {launched:.2} pixels of the nearest plane apart"
            );
            // The grid's cells fit its extent, so they come out a little under the asked
            // spacing when the budget does not bind, a little over when it just does.
            let budget = opts.sweep.light_rays;
            // The printed two decimals must show the difference.
            let bound = launched > asked * 1.01;
            if bound && budget < MAX_LIGHT_RAYS {
                println!(
                    ", not {asked}: the budget of {budget} rays per screen pixel binds \
                     (--light-rays, up to {MAX_LIGHT_RAYS})"
                );
            } else if bound {
                println!(
                    ", not {asked}: the most rays there can be, {MAX_LIGHT_RAYS} per screen \
                     pixel, bind"
                );
            } else {
                println!();
            }
        }
        let c = stats.clamps;
        println!(
            "light transport: {}; clamps (pixel-planes): light direction {}, light rays \
             turned back and dropped {}, viewing direction {}, gain {}",
            stats.light_transport.name(),
            c.light_direction,
            c.light_dropped,
            c.view_direction,
            c.gain
        );
    }
    if args.with_baseline {
        let main_ms = main_pass_ms(&frame);
        let ea = renderer.render(Model::Ea, &camera, &opts)?;
        let ea_ms = main_pass_ms(&ea);
        println!("baseline: ea raymarch {ea_ms:.3} ms");
        if ea_ms > 0.0 {
            println!(
                "ratio {} / ea: {:.2} (same volume, view, image and sample distance)",
                model.name(),
                main_ms / ea_ms
            );
        }
    }
    write_dumps(&frame, &camera, &dump_dir)?;
    println!("wrote {}", args.output.display());
    drop(renderer);
    finish(ctx)
}

/// Where `--dump BUFFER@PLANE` is written in `dir`.
fn dump_path(dir: &Path, buffer: StateBuffer, plane: u32) -> std::path::PathBuf {
    dir.join(format!("{}-{plane}.exr", buffer.name()))
}

/// Writes the --dump state buffers as EXR. Each file's header says where the buffer lives:
/// the plane's index and view depth, the world-space plane `n·p = d` (n the camera's
/// forward, d = n·eye + depth) and the camera; the log line says the same.
pub fn write_dumps(frame: &refrakt::render::Frame, camera: &Camera, dir: &Path) -> Result<()> {
    use output::HeaderValue::{Text, Vec3 as V3, F32, I32};
    if frame.dumps.is_empty() {
        return Ok(());
    }
    let (eye, forward, _, _) = camera.frame();
    let t = camera.target;
    // (+ 0.0 turns -0 into 0 for the log.)
    let v = |v: glam::Vec3| format!("({:.4},{:.4},{:.4})", v.x + 0.0, v.y + 0.0, v.z + 0.0);
    println!(
        "dump camera: eye {} target {} vertical fov {}°",
        v(eye),
        v(t),
        camera.fov_y
    );
    let spacing = frame.sweep.as_ref().map(|s| s.planes.spacing);
    for d in &frame.dumps {
        let path = dump_path(dir, d.buffer, d.plane);
        let offset = forward.dot(eye) + d.depth;
        let mut attrs = vec![
            ("refrakt.buffer", Text(d.buffer.name().into())),
            ("refrakt.plane", I32(d.plane as i32)),
            ("refrakt.viewDepth", F32(d.depth)),
            ("refrakt.planeNormal", V3(forward.to_array())),
            ("refrakt.planeOffset", F32(offset)),
            ("refrakt.cameraEye", V3(eye.to_array())),
            ("refrakt.cameraTarget", V3(t.to_array())),
            ("refrakt.cameraFovY", F32(camera.fov_y)),
        ];
        // The pass for plane k leaves the viewing rays on plane k+1 (see Dump::depth).
        let mut next = String::new();
        if let (StateBuffer::ViewPosition, Some(s)) = (d.buffer, spacing) {
            let depth = d.depth + s;
            attrs.push(("refrakt.positionsViewDepth", F32(depth)));
            attrs.push(("refrakt.positionsPlaneOffset", F32(offset + s)));
            next = format!(
                "; positions on the next plane: view depth {depth:.4}, d={:.4}",
                offset + s
            );
        }
        output::write_pixels_with_attributes(d.width, d.height, &d.pixels, &path, &attrs)?;
        println!(
            "dumped {} after plane {} (view depth {:.4}, world plane n={} d={offset:.4}{next}) to {}",
            d.buffer.name(),
            d.plane,
            d.depth,
            v(forward),
            path.display()
        );
    }
    Ok(())
}

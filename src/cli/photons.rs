//! `refrakt photons`: the CPU photon tracer's reference image.

use std::process::ExitCode;

use anyhow::{bail, ensure, Result};

use refrakt::output;
use refrakt::scene::LoadedScene;

use super::args::*;
use super::scene_args::*;

pub fn photons(args: &PhotonsArgs) -> Result<ExitCode> {
    use refrakt::photons::{self, PhotonOptions};
    let ext = args.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        bail!(
            "{}: the photon tracer writes linear EXR only; use a .exr file name",
            args.output.display()
        );
    }
    output::format_for(&args.output)?;
    refuse_unused_flags(&args.scene)?;
    let popts = PhotonOptions {
        photons_per_pixel: args.photons_per_pixel,
        step: args.step,
        seed: args.seed,
        jitter: args.jitter,
        threads: args.threads.unwrap_or(0),
        max_steps: Some(args.max_steps),
        plane_flux: args.plane_flux,
    };
    ensure!(
        args.max_steps.is_finite() && args.max_steps > 0.0,
        "--max-steps {}: must be a positive number",
        args.max_steps
    );
    popts.validate()?;
    let scene = scene_from_args(&args.scene)?;
    let data_dir = data_dir(&args.scene);
    refrakt::files::check_outputs(&[("-o", &args.output)], &scene.input_files(&data_dir))?;
    let LoadedScene {
        name,
        volume,
        tf,
        camera,
        opts,
        ..
    } = scene.load_all(&data_dir, None)?;
    let planes = photons::planes(&volume, &camera, &opts)?;
    let depth = match (args.plane, args.depth) {
        (Some(k), _) => photons::plane_depth(&volume, &camera, &opts, k)?,
        (None, Some(z)) => z,
        (None, None) => bail!("give --plane K or --depth Z"),
    };
    // Rows of photons done, on a terminal only (indicatif draws nothing otherwise).
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "tracing photons {bar:30} {pos}/{len} rows ({elapsed}, ETA {eta})",
    ) {
        bar.set_style(style);
    }
    let progress = |done: u64, rows: u64| {
        bar.set_length(rows);
        bar.set_position(done);
    };
    let img =
        photons::trace_irradiance(&volume, &tf, &camera, &opts, depth, &popts, Some(&progress))?;
    bar.finish_and_clear();
    output::write_pixels(img.width, img.height, &img.pixels, &args.output)?;
    println!(
        "{} of the {} scene ({}x{}x{}, transfer functions {}) on the plane at view \
         depth {depth:.5}{}, {}x{}",
        if args.plane_flux {
            "flux per unit plane area"
        } else {
            "fluence"
        },
        name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        match args.plane {
            Some(k) => format!(" (plane {k} of 0..{})", planes.count - 1),
            None => String::new(),
        },
        img.width,
        img.height
    );
    println!("{}", img.summary());
    println!("wrote {}", args.output.display());
    Ok(ExitCode::SUCCESS)
}

/// The scene flags the photon tracer does not read (it traces the refractive model's
/// light through the volume and its η; no viewing rays, surfaces, environment or tone
/// mapping): refused, as `render` refuses flags of another model, rather than ignored.
fn refuse_unused_flags(a: &SceneArgs) -> Result<()> {
    // (Nor the models' own options: the photon tracer follows the sweep's light, which
    // has none.)
    refuse_flags_not_read(
        a,
        &[
            ("--model", a.model.is_some()),
            ("--no-preintegration", a.no_preintegration),
            ("--background", a.background.is_some()),
            ("--add-light", !a.add_light.is_empty()),
            ("--ambient-table", a.ambient_table.is_some()),
            ("--softness", a.softness.is_some()),
            ("--roughness", a.roughness.is_some()),
            ("--specular", a.specular.is_some()),
            ("--light-transport", a.light_transport.is_some()),
            ("--light-rays", a.light_rays.is_some()),
            ("--light-spacing", a.light_spacing.is_some()),
            ("--reflections", a.reflections.is_some()),
            ("--clip", a.clip.is_some()),
            ("--env", a.env.is_some()),
            ("--env-rotation", a.env_rotation.is_some()),
            ("--exposure", a.exposure.is_some()),
            ("--tonemap", a.tonemap.is_some()),
        ],
        "the photon tracer",
        "it traces the refractive model's light through the volume onto one plane, with \
         the scene's volume, transfer functions, camera, image size, sample distance, light \
         and --eta-scale",
    )
}

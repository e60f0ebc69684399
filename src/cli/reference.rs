//! `refrakt reference`: the CPU reference renderer's camera image (issue 32 item 5).

use std::process::ExitCode;

use anyhow::{ensure, Result};

use refrakt::output;
use refrakt::scene::LoadedScene;

use super::args::*;
use super::scene_args::*;

pub fn reference(args: &ReferenceArgs) -> Result<ExitCode> {
    use refrakt::photons::{self, ReferenceOptions};
    output::format_for(&args.output)?;
    refuse_unused_flags(&args.scene)?;
    ensure!(
        args.max_steps.is_finite() && args.max_steps > 0.0,
        "--max-steps {}: must be a positive number",
        args.max_steps
    );
    let ropts = ReferenceOptions {
        photons_per_voxel: args.photons_per_voxel,
        light_bins: args.light_bins,
        step: args.step,
        rays_per_pixel: args.rays_per_pixel,
        bounces: args.bounces,
        cubic_eta: args.eta_interpolation == "cubic",
        threads: args.threads.unwrap_or(0),
        max_steps: Some(args.max_steps),
    };
    ropts.validate()?;
    let scene = scene_from_args(&args.scene)?;
    let data_dir = data_dir(&args.scene);
    refrakt::files::check_outputs(&[("-o", &args.output)], &scene.input_files(&data_dir))?;
    let LoadedScene {
        name,
        volume,
        tf,
        env,
        env_name,
        camera,
        opts,
        tone,
        ..
    } = scene.load_all(&data_dir, None)?;
    // Rows of photons and of pixels done, on a terminal only (indicatif draws nothing
    // otherwise).
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} rows ({elapsed})")
    {
        bar.set_style(style);
    }
    let progress = |phase: &str, done: u64, rows: u64| {
        if bar.length() != Some(rows) {
            bar.set_length(rows);
        }
        bar.set_message(phase.to_string());
        bar.set_position(done);
    };
    let img = photons::render_reference(
        &volume,
        &tf,
        env.as_ref(),
        &camera,
        &opts,
        &ropts,
        Some(&progress),
    )?;
    bar.finish_and_clear();
    let frame = refrakt::render::Frame {
        width: img.width,
        height: img.height,
        pixels: img.pixels.clone(),
        timings: Default::default(),
        max_steps: 0,
        dumps: Vec::new(),
        sweep: None,
    };
    output::write(&frame, &args.output, &tone)?;
    println!(
        "reference image of the {} scene ({}x{}x{}, transfer functions {}, environment {}), \
         {}x{}, {} viewing ray(s) per pixel, step {} voxels",
        name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        tf.name,
        env_name,
        img.width,
        img.height,
        ropts.rays_per_pixel * ropts.rays_per_pixel,
        ropts.step
    );
    println!("{}", img.summary());
    println!("wrote {}", args.output.display());
    Ok(ExitCode::SUCCESS)
}

/// The scene flags the reference renderer does not read (it renders the refractive
/// model's image formation without the sweep's own choices: no specular highlight, no
/// soft-shadow kernel, no light transport of its own to choose): refused, as `render`
/// refuses flags of another model, rather than ignored.
fn refuse_unused_flags(a: &SceneArgs) -> Result<()> {
    refuse_flags_not_read(
        a,
        &[
            ("--model", a.model.is_some()),
            ("--no-preintegration", a.no_preintegration),
            ("--ambient-table", a.ambient_table.is_some()),
            ("--softness", a.softness.is_some()),
            ("--roughness", a.roughness.is_some()),
            ("--specular", a.specular.is_some()),
            ("--light-transport", a.light_transport.is_some()),
            ("--light-rays", a.light_rays.is_some()),
            ("--light-spacing", a.light_spacing.is_some()),
        ],
        "the reference renderer",
        "it renders the refractive model's image formation with exact light: the scene's \
         volume, transfer functions, camera, image size, lights, ambient level, background \
         or environment, reflections, clipping plane, --eta-scale and tone mapping; no \
         specular highlight",
    )
}

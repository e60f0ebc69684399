//! `refrakt photons`: the CPU photon tracer's reference image.

use std::process::ExitCode;

use anyhow::{bail, Result};

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
    let popts = PhotonOptions {
        photons_per_pixel: args.photons_per_pixel,
        step: args.step,
        seed: args.seed,
        jitter: args.jitter,
        threads: args.threads.unwrap_or(0),
    };
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
    let img = photons::trace_irradiance(&volume, &tf, &camera, &opts, depth, &popts)?;
    output::write_pixels(img.width, img.height, &img.pixels, &args.output)?;
    println!(
        "irradiance of the {} scene ({}x{}x{}, transfer functions {}) on the plane at view \
         depth {depth:.5}{}, {}x{}",
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

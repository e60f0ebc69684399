//! `refrakt view`: the interactive viewer.

use std::process::ExitCode;

use anyhow::{bail, Result};

use refrakt::output;
use refrakt::viewer::{self, ViewOptions};
use refrakt::vk::ContextDesc;

use super::args::*;
use super::scene_args::*;

pub fn view(desc: &ContextDesc, args: ViewArgs) -> Result<ExitCode> {
    if let Some(code) = list_and_exit(&args.scene)? {
        return Ok(code);
    }
    if let Some(path) = &args.screenshot {
        output::format_for(path)?;
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let resize = args.resize.as_deref().map(parse_resize).transpose()?;
    if !(args.preview_budget.is_finite() && args.preview_budget >= 0.0) {
        bail!(
            "--preview-budget {}: expected a frame time in ms, 0 or more (0: no previews)",
            args.preview_budget
        );
    }
    match args.interrupt_refinement {
        Some(0) => bail!("--interrupt-refinement must be at least 1 (a batch of planes)"),
        Some(_) if args.preview_budget == 0.0 => bail!(
            "--interrupt-refinement needs previews: with --preview-budget 0 every frame is \
             rendered whole, not refined in batches"
        ),
        _ => {}
    }
    if !args.screenshot_dir.is_dir() {
        bail!(
            "--screenshot-dir {}: the folder does not exist",
            args.screenshot_dir.display()
        );
    }
    let scene_args = args.scene.clone();
    if let Some(path) = &args.screenshot {
        let inputs = scene_from_args(&scene_args)?.input_files(&data_dir(&scene_args));
        refrakt::files::check_outputs(&[("--screenshot", path)], &inputs)?;
    }
    let scene = build_scene(&scene_args, None)?;
    for n in &scene.notes {
        println!("{n}");
    }
    let options = ViewOptions {
        vsync: !args.no_vsync,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
        resize,
        screenshot_dir: args.screenshot_dir.clone(),
        watch: !args.no_watch,
        preview_budget_ms: (args.preview_budget > 0.0).then_some(args.preview_budget),
        drag: args.drag,
        interrupt_refinement: args.interrupt_refinement,
        panel: !args.no_panel,
        axes: !args.no_axes,
    };
    let report = viewer::run(
        desc.clone(),
        scene,
        Box::new(move || build_scene(&scene_args, None)),
        options,
    )?;
    if report.validation_messages > 0 {
        eprintln!(
            "validation: {} message(s) reported (see above)",
            report.validation_messages
        );
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

//! `refrakt` command line: `info` (devices), `render` (one frame to an image, with GPU
//! timings), `view` (the interactive viewer), `photons` (the CPU photon tracer's reference),
//! `generate` (write a stand-in volume) and `bench` (the timing tables). The commands live
//! in `src/cli/`, one module each.

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use cli::args::{BenchCommand, Cli, Command};
use refrakt::vk::ContextDesc;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    let desc = ContextDesc::from_env(cli.gpu.validate, cli.gpu.device.clone())?;
    match cli.command {
        Command::Info => cli::info::info(&desc),
        Command::Render(args) => cli::render::render(&desc, &args),
        Command::View(args) => cli::view::view(&desc, *args),
        Command::Photons(args) => cli::photons::photons(&args),
        Command::Generate(args) => cli::bench::generate(&args),
        Command::Bench(BenchCommand::Thesis(args)) => cli::bench::bench_thesis(&desc, &args),
        Command::Bench(BenchCommand::Scaling(args)) => cli::bench::bench_scaling(&desc, &args),
    }
}

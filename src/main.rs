//! `refrakt` command line: `info` (devices), `render` (one frame to an image, with GPU
//! timings), `view` (the interactive viewer), `photons` (the CPU photon tracer's reference),
//! `generate` (write a stand-in volume), `bench` (the timing tables, lever A/B and
//! report comparison) and `precompute` (the ambient-scattering table). The commands live
//! in `src/cli/`, one module each.

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use cli::args::{BenchCommand, Cli, Command, PrecomputeCommand};
use refrakt::vk::ContextDesc;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help and --version print in full; a usage error is one line like every other
        // error (clap adds a usage excerpt and a pointer to --help below it).
        Err(e) if e.use_stderr() => {
            // The message and its details (the missing arguments, a tip), up to the usage.
            let text = e.render().to_string();
            let message: Vec<&str> = text
                .lines()
                .take_while(|l| !l.starts_with("Usage:"))
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
                .collect();
            let line = format!("{} (see --help)", message.join(" ").trim_end_matches('.'));
            eprintln!("{}", one_line(&line, MAX_ERROR_CHARS));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            let prefix = "error: ";
            let line = one_line(&chain_text(&e), MAX_ERROR_CHARS - prefix.len());
            eprintln!("{prefix}{line}");
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, "context: cause: ...", leaving out a cause whose text the one
/// before it already carries (an image decoder's error repeats its I/O source, which the
/// chain then gave a second time).
fn chain_text(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if parts.last().is_some_and(|p| p.contains(text.trim())) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

/// Longest error line printed, whole (issue 33): the start (file and reason) and the end (a parser's
/// "expected ...") survive; what a parser quotes of a garbage file in between is cut.
const MAX_ERROR_CHARS: usize = 400;

/// `msg` as one terminal-safe line: line breaks (a TOML error's source excerpt spans four
/// lines) become " | ", other control characters are escaped (a header of NUL bytes
/// prints as `\0...`), and the middle of an over-long message is cut, saying how much.
fn one_line(msg: &str, max: usize) -> String {
    let mut flat = String::new();
    for line in msg
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
    {
        if !flat.is_empty() {
            flat.push_str(" | ");
        }
        for c in line.chars() {
            if c.is_control() {
                flat.extend(c.escape_default());
            } else {
                flat.push(c);
            }
        }
    }
    let chars: Vec<char> = flat.chars().collect();
    if chars.len() <= max {
        return flat;
    }
    // The marker is counted in `max`: the line, cut, is at most `max` characters.
    let marker = |cut: usize| format!(" [... {cut} characters cut ...] ");
    let keep = max.saturating_sub(marker(chars.len()).chars().count());
    let (head, tail) = (keep * 3 / 4, keep - keep * 3 / 4);
    let cut = chars.len() - head - tail;
    let mut out: String = chars[..head].iter().collect();
    out.push_str(&marker(cut));
    out.extend(&chars[chars.len() - tail..]);
    out
}

fn run(cli: Cli) -> Result<ExitCode> {
    let desc = ContextDesc::from_env(cli.gpu.validate, cli.gpu.device.clone())?;
    match cli.command {
        Command::Info => cli::info::info(&desc),
        Command::Render(args) => cli::render::render(&desc, &args),
        Command::View(args) => cli::view::view(&desc, *args),
        Command::Photons(args) => cli::photons::photons(&args),
        Command::Reference(args) => cli::reference::reference(&args),
        Command::Generate(args) => cli::bench::generate(&args),
        Command::Bench(BenchCommand::Thesis(args)) => cli::bench::bench_thesis(&desc, &args),
        Command::Bench(BenchCommand::Scaling(args)) => cli::bench::bench_scaling(&desc, &args),
        Command::Bench(BenchCommand::Variants(args)) => cli::bench::bench_variants(&desc, &args),
        Command::Bench(BenchCommand::Compare(args)) => cli::bench::bench_compare(&args),
        Command::Bench(BenchCommand::Models(args)) => cli::bench::bench_models(&desc, &args),
        Command::Precompute(PrecomputeCommand::Ambient(args)) => cli::precompute::ambient(&args),
    }
}

#[cfg(test)]
mod tests {
    use super::{chain_text, one_line};

    #[test]
    fn a_cause_already_in_its_context_is_not_said_twice() {
        let io = std::io::Error::other("Not enough bytes");
        let e = anyhow::Error::new(io)
            .context("Format error decoding Jpeg: Not enough bytes")
            .context("environment map x.jpg: not a readable image");
        assert_eq!(
            chain_text(&e),
            "environment map x.jpg: not a readable image: Format error decoding Jpeg: Not \
             enough bytes"
        );
        let e = anyhow::anyhow!("inner").context("outer");
        assert_eq!(chain_text(&e), "outer: inner");
    }

    #[test]
    fn errors_print_as_one_bounded_line() {
        assert_eq!(
            one_line("a.toml: bad\n  | x\n\n  ^ here", 400),
            "a.toml: bad |   | x |   ^ here"
        );
        assert_eq!(
            one_line("f: \0\0\u{1b}[2J", 400),
            "f: \\u{0}\\u{0}\\u{1b}[2J"
        );
        let long = format!("f.toml: {} expected a table", "z".repeat(1_000_000));
        let l = one_line(&long, 400);
        assert!(
            l.chars().count() <= 400 && !l.contains('\n'),
            "{}",
            l.chars().count()
        );
        assert!(
            l.starts_with("f.toml: zz") && l.ends_with("expected a table"),
            "{l}"
        );
        assert!(l.contains("characters cut"));
    }
}

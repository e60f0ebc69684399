//! The models' declared options as command-line flags (issue 34 item 1): every
//! [`ModelOption`] of every model in the registry becomes `--<name>`, with its help, the
//! models that take it and its default, so a model's options are written once, in its
//! folder, and no flag here names one.

use anyhow::Result;
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};

use refrakt::render::{declared_options, ModelOption, ModelOptions};

/// Where `--help` lists them.
pub const HEADING: &str = "Model options (each says which --model takes it)";

/// The declared options given on the command line, as written (parsed and checked by
/// [`ModelFlags::options`], so that an error names the flag).
#[derive(Clone, Debug, Default)]
pub struct ModelFlags {
    given: Vec<(&'static ModelOption, String)>,
}

impl ModelFlags {
    /// Their values, each checked by its declaration.
    pub fn options(&self) -> Result<ModelOptions> {
        let mut values = ModelOptions::default();
        for (o, text) in &self.given {
            let v = o
                .parse(text)
                .map_err(|e| anyhow::anyhow!("{}: {e:#}", o.flag))?;
            values.set(o, v)?;
        }
        Ok(values)
    }

    /// The flags given.
    pub fn flags_given(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.given.iter().map(|(o, _)| o.flag)
    }
}

impl FromArgMatches for ModelFlags {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = Self::default();
        flags.update_from_arg_matches(matches)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        for (o, _) in declared_options() {
            if let Some(text) = matches.get_one::<String>(o.name()) {
                self.given.retain(|(g, _)| g.flag != o.flag);
                self.given.push((o, text.clone()));
            }
        }
        Ok(())
    }
}

impl Args for ModelFlags {
    fn augment_args(mut cmd: Command) -> Command {
        for (o, models) in declared_options() {
            let names: Vec<&str> = models.iter().map(|m| m.name()).collect();
            let default = if o.integer {
                format!("{}", o.default as u64)
            } else {
                format!("{}", o.default)
            };
            cmd = cmd.arg(
                Arg::new(o.name())
                    .long(o.name())
                    .value_name(o.value_name)
                    .action(ArgAction::Set)
                    .allow_negative_numbers(true)
                    .help_heading(HEADING)
                    .help(format!(
                        "{} (--model {}) [default: {default}]",
                        o.help,
                        names.join(", ")
                    )),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

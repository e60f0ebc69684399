//! Options a model declares from its own folder (issue 34 item 1): each is a number with
//! a name, a default, a help line and a check. The name gives the command-line flag
//! (`--ao-radius`) and the scene file's `[render]` key (`ao_radius`); the CLI
//! (`cli/model_flags.rs`), scene files (`scene/file.rs`) and the refusal of options a
//! model does not take (`scene/applies.rs`) read the declarations through the registry
//! ([`super::Model::options`], [`declared_options`]), so a model's options name it nowhere
//! outside its folder. Their values travel in [`RenderOptions::models`], keyed by name;
//! a model reads its own through its typed view (e.g. `ao::AoOptions::of`).

use std::collections::BTreeMap;

use anyhow::{ensure, Context as _, Result};

use super::{Model, RenderOptions};

/// One option of one or more models (the scattering pair `--g`, `--albedo` is declared
/// once, in render/options.rs, and listed by both scattering models).
#[derive(Debug)]
pub struct ModelOption {
    /// The command-line flag, `--<name>`; the name, with `_` for `-`, is the scene
    /// file's `[render]` key and the key of its value.
    pub flag: &'static str,
    /// The value's name in `--help` ("VOXELS").
    pub value_name: &'static str,
    /// What it does, for `--help` (the models that take it and the default are added).
    pub help: &'static str,
    /// Its value when none is given.
    pub default: f64,
    /// Whether only whole numbers are taken.
    pub integer: bool,
    /// Refuses a value the model cannot take, saying why (the caller names the option).
    pub check: fn(f64) -> Result<()>,
}

impl ModelOption {
    /// The flag without its `--` ("ao-radius").
    pub fn name(&self) -> &'static str {
        self.flag.trim_start_matches('-')
    }

    /// The scene file's `[render]` key ("ao_radius").
    pub fn key(&self) -> String {
        self.name().replace('-', "_")
    }

    /// `text` as this option's value, checked (errors say why, not which option: the
    /// front end adds the flag or the key).
    pub fn parse(&self, text: &str) -> Result<f64> {
        let v: f64 = text
            .trim()
            .parse()
            .ok()
            .with_context(|| format!("'{text}' is not a number"))?;
        self.checked(v)
    }

    /// `v` if this option takes it.
    pub fn checked(&self, v: f64) -> Result<f64> {
        ensure!(v.is_finite(), "{v} is not a finite number");
        ensure!(
            !self.integer || (v.fract() == 0.0 && v >= 0.0 && v <= u32::MAX as f64),
            "{v} is not a whole number from 0 to {}",
            u32::MAX
        );
        (self.check)(v)?;
        Ok(v)
    }
}

/// The declared options' values a frame asks for, keyed by option name; an option not
/// set has its declared default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelOptions(BTreeMap<&'static str, f64>);

impl ModelOptions {
    /// The value of `option` (its default when not set).
    pub fn get(&self, option: &ModelOption) -> f64 {
        self.0.get(option.name()).copied().unwrap_or(option.default)
    }

    /// Set `option` to `value`, refused (naming the option's flag) if it does not take it.
    pub fn set(&mut self, option: &'static ModelOption, value: f64) -> Result<()> {
        self.set_as(option, value, option.flag)
    }

    /// [`Self::set`], naming the option as the user wrote it (`written`: the flag, or a
    /// scene file's "[render] ao_radius").
    pub fn set_as(
        &mut self,
        option: &'static ModelOption,
        value: f64,
        written: &str,
    ) -> Result<()> {
        let v = option.checked(value).with_context(|| written.to_string())?;
        self.0.insert(option.name(), v);
        Ok(())
    }

    /// Take every value set in `other` (values already checked when they were set).
    pub fn merge(&mut self, other: &ModelOptions) {
        self.0.extend(other.0.iter().map(|(k, v)| (*k, *v)));
    }
}

impl RenderOptions {
    /// The value of `option` in this frame's model options.
    pub fn model_option(&self, option: &ModelOption) -> f64 {
        self.models.get(option)
    }
}

/// Every option some model declares, once each (in [`Model::ALL`]'s order), with the
/// models that take it.
pub fn declared_options() -> Vec<(&'static ModelOption, Vec<Model>)> {
    let mut all: Vec<(&'static ModelOption, Vec<Model>)> = Vec::new();
    for m in Model::ALL {
        for &o in m.options() {
            match all.iter_mut().find(|(d, _)| d.flag == o.flag) {
                Some((_, models)) => models.push(m),
                None => all.push((o, vec![m])),
            }
        }
    }
    all
}

/// The declared option named `name` (as its flag without `--`, or as its scene key).
pub fn find_option(name: &str) -> Option<&'static ModelOption> {
    let name = name.replace('_', "-");
    declared_options()
        .into_iter()
        .map(|(o, _)| o)
        .find(|o| o.name() == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_with_one_name_are_one_declaration_and_their_defaults_are_taken() {
        for (o, models) in declared_options() {
            assert!(!models.is_empty());
            o.checked(o.default)
                .unwrap_or_else(|e| panic!("{}'s default {}: {e:#}", o.flag, o.default));
            assert!(o.flag.starts_with("--"), "{}", o.flag);
            assert_eq!(find_option(&o.key()).map(|f| f.flag), Some(o.flag));
            // Two models listing an option of the same name list the same declaration.
            for m in &models {
                let theirs = m.options().iter().find(|d| d.flag == o.flag).unwrap();
                assert!(
                    std::ptr::eq(*theirs, o),
                    "{} declares {} again",
                    m.name(),
                    o.flag
                );
            }
        }
    }
}

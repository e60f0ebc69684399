//! Settings that belong to some models only, or to the forward light transport only: given
//! with another model (or the backward transport) they are refused by name, never silently
//! ignored — on the command line and in scene files alike. Which model takes which setting
//! is each model's declaration (`Model::takes_flag`: its options and flags, the registry).

use anyhow::{bail, ensure, Result};

use crate::render::{LightTransport, Model};

/// A setting as the user gave it: its command-line flag (what the models' declarations
/// list) and how it was written (the flag itself, or a scene file's key).
#[derive(Clone, Debug)]
pub struct Given {
    pub flag: &'static str,
    pub written: String,
}

impl Given {
    /// A flag given on the command line.
    pub fn flag(flag: &'static str) -> Self {
        Self {
            flag,
            written: flag.to_string(),
        }
    }
}

/// The light rays' own settings: the backward transport propagates light plane to plane
/// and has no rays.
const FORWARD_ONLY: [&str; 2] = ["--light-rays", "--light-spacing"];

/// Refuses `given` settings that `model` does not take (naming the models that do), and the
/// light rays' settings with the backward and eikonal light transports.
pub fn refuse_what_does_not_apply(
    model: Model,
    transport: LightTransport,
    given: &[Given],
) -> Result<()> {
    // (settings, the models that take them), grouped by those models.
    let mut refused: Vec<(Vec<&str>, Vec<&str>)> = Vec::new();
    for g in given {
        if model.takes_flag(g.flag) {
            continue;
        }
        let owners: Vec<&str> = Model::ALL
            .iter()
            .filter(|m| m.takes_flag(g.flag))
            .map(|m| m.name())
            .collect();
        if owners.is_empty() {
            continue;
        }
        match refused.iter_mut().find(|(_, o)| *o == owners) {
            Some((written, _)) => written.push(&g.written),
            None => refused.push((vec![&g.written], owners)),
        }
    }
    let said: Vec<String> = refused
        .iter()
        .map(|(written, owners)| {
            format!(
                "{} only appl{} to --model {}",
                written.join(", "),
                if written.len() > 1 { "y" } else { "ies" },
                owners.join(", ")
            )
        })
        .collect();
    ensure!(
        said.is_empty(),
        "{}, not {}{}",
        said.join("; "),
        model.name(),
        if model.uses_light() {
            ""
        } else {
            " (which has no light, plane sweep, refraction or environment)"
        }
    );
    if model == Model::Refract && transport == LightTransport::Eikonal {
        if let Some(g) = given.iter().find(|g| g.flag == "--softness") {
            bail!(
                "{} does not apply to the eikonal light transport: its light is the light \
                 simulator's, which has no softness filter (soft shadows are the forward and \
                 backward transports')",
                g.written
            );
        }
    }
    if model == Model::Refract && transport != LightTransport::Forward {
        let rays: Vec<&str> = given
            .iter()
            .filter(|g| FORWARD_ONLY.contains(&g.flag))
            .map(|g| g.written.as_str())
            .collect();
        ensure!(
            rays.is_empty(),
            "{} only appl{} to the forward light transport (its light rays); the {} \
             transport {}",
            rays.join(", "),
            if rays.len() > 1 { "y" } else { "ies" },
            transport.name(),
            match transport {
                LightTransport::Eikonal => "reads the light from the simulated light volume",
                _ => "propagates the light from plane to plane",
            }
        );
    }
    Ok(())
}

//! The registry of optical models: the one place that lists them. Each model declares
//! itself from its own folder (an [`OpticalModel`] `static`: name, lights, the shared
//! data it reads, its checks, its pass); [`Model`] is the handle the CLI, scene files,
//! viewer and benchmarks pass around, and [`Model::declaration`] finds a model's
//! declaration.
//!
//! Adding a model: a folder under `render/` with its `ModelPass`, its [`OpticalModel`]
//! `static` and its options' `static`s ([`ModelOption`]: flags and scene keys follow from
//! them), its `mod` line below, a variant, its line in [`Model::ALL`] and in
//! [`Model::declaration`]; its shaders in `glsl/` (build.rs compiles every file there).

// The models' folders. They lie beside this file, under `render/` (`#[path]`: without it
// Rust would look under `render/registry/`), and are declared here so that this file is
// the one that lists them. Their module parent is this one, so a model's `super::x`
// reaches `render`'s items through the glob below.
#[path = "ambient/mod.rs"]
pub mod ambient;
#[path = "ao/mod.rs"]
pub mod ao;
#[path = "ea/mod.rs"]
mod ea;
#[path = "eikonal/mod.rs"]
pub mod eikonal;
#[path = "refract/mod.rs"]
pub mod refract;
#[path = "single/mod.rs"]
pub mod single;

use super::*;

use super::model::OpticalModel;
use super::model_options::ModelOption;

/// What lights a model takes: [`Model::light_support`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightSupport {
    /// How many (0: the model is unlit and ignores them).
    pub max: usize,
    /// Whether point lights are among them (else directional only).
    pub point: bool,
}

impl LightSupport {
    /// An unlit model's.
    pub const NONE: Self = Self {
        max: 0,
        point: false,
    };
    /// One directional light.
    pub const ONE_DIRECTIONAL: Self = Self {
        max: 1,
        point: false,
    };
}

/// The flags that give lights (`--light` repeated, the main light's colour): taken by
/// every model that takes lights ([`OpticalModel::lights`]).
const LIGHT_FLAGS: [&str; 2] = ["--light", "--light-colour"];

/// Rendering models `refrakt render --model` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Model {
    /// Emission–absorption ray marcher, the baseline.
    Ea,
    /// The refractive plane sweep (thesis ch. 4, Algorithm 1).
    Refract,
    /// Volumetric ambient occlusion from a 3D summed-area table (render::ao).
    Ao,
    /// Single scattering with shadows from a transmittance cache (render::single).
    Single,
    /// Ambient scattering: multiple scattering in a sphere around each sample from a
    /// preintegrated Monte-Carlo table, soft shadows by tube marching (render::ambient).
    Ambient,
    /// Eikonal rendering: a simulated light volume, viewing rays along the ray equation
    /// (render::eikonal).
    Eikonal,
}

impl Model {
    /// Every model, in the order `bench models` compares them (EA first: the ratios'
    /// base).
    pub const ALL: [Model; 6] = [
        Model::Ea,
        Model::Ao,
        Model::Single,
        Model::Ambient,
        Model::Refract,
        Model::Eikonal,
    ];

    /// The model called `name` (as [`Model::name`] gives it).
    pub fn from_name(name: &str) -> Option<Model> {
        Model::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The models `bench models` times by default and the viewer's `m` key cycles
    /// through: all but the experimental ones ([`Model::experimental`]), in [`Model::ALL`]'s order.
    pub fn benched() -> Vec<Model> {
        Model::ALL
            .into_iter()
            .filter(|m| m.experimental().is_none())
            .collect()
    }

    /// Why the model is left out of `bench models` and the viewer's `m` key, if it is.
    pub fn experimental(self) -> Option<&'static str> {
        self.declaration().experimental
    }

    /// The model after this one in [`Model::benched`], wrapping round: the viewer's `m`
    /// key (from an experimental model, the first).
    pub fn next(self) -> Model {
        let models = Model::benched();
        match models.iter().position(|&m| m == self) {
            Some(i) => models[(i + 1) % models.len()],
            None => models[0],
        }
    }

    /// Whether the model takes the command-line flag `flag` ("--ao-radius"), of those
    /// that some models take and others refuse: the light's (a model that takes lights),
    /// its options' flags and the other flags its declaration lists.
    pub fn takes_flag(self, flag: &str) -> bool {
        let d = self.declaration();
        (LIGHT_FLAGS.contains(&flag) && self.uses_light())
            || d.flags.contains(&flag)
            || d.options.iter().any(|o| o.flag == flag)
    }

    /// The options the model declares (its folder's [`ModelOption`]s).
    pub fn options(self) -> &'static [&'static ModelOption] {
        self.declaration().options
    }

    /// One line for `--help`.
    pub fn summary(self) -> &'static str {
        self.declaration().summary
    }

    /// The model's declaration, from its folder: the registry's one list.
    pub(crate) fn declaration(self) -> &'static OpticalModel {
        match self {
            Model::Ea => &ea::EA,
            Model::Refract => &refract::REFRACT,
            Model::Ao => &ao::AO,
            Model::Single => &single::SINGLE,
            Model::Ambient => &ambient::AMBIENT,
            Model::Eikonal => &eikonal::EIKONAL,
        }
    }

    /// Whether the model lights the volume with [`RenderOptions::lights`] (a light change
    /// can cost it a rebuild); the others ignore the lights.
    pub fn uses_light(self) -> bool {
        self.light_support().max > 0
    }

    /// How many lights the model takes (the main light first) and whether point lights
    /// are among them (each model's declaration says why).
    pub fn light_support(self) -> LightSupport {
        self.declaration().lights
    }

    /// Whether the model has a phase function (a phase-function change applies).
    pub fn has_phase_function(self) -> bool {
        self.declaration().phase_function
    }

    pub fn name(self) -> &'static str {
        self.declaration().name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_distinct_and_find_their_model() {
        for m in Model::ALL {
            assert_eq!(Model::from_name(m.name()), Some(m), "{}", m.name());
            assert!(!m.summary().is_empty(), "{} has no summary", m.name());
        }
        let mut names: Vec<_> = Model::ALL.iter().map(|m| m.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Model::ALL.len(), "two models share a name");
        assert_eq!(Model::from_name("sweep"), None);
    }

    #[test]
    fn the_viewers_m_key_cycles_as_the_readme_says() {
        // README, Viewer: "model: refract → ea → ao → single → ambient (cycles)".
        let mut m = Model::from_name("refract").unwrap();
        let mut seen = vec![m.name()];
        for _ in 0..Model::benched().len() {
            m = m.next();
            seen.push(m.name());
        }
        assert_eq!(
            seen,
            ["refract", "ea", "ao", "single", "ambient", "refract"]
        );
        // The experimental eikonal model is not in the cycle; from it, `m` goes to the
        // first.
        assert_eq!(Model::Eikonal.next(), Model::Ea);
    }
}

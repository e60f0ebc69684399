//! What to render and how to show it: everything `refrakt render` and `refrakt view` take
//! from the command line, built in one place (`main.rs`, `build_scene`) so both commands
//! see the same scene.

use std::path::PathBuf;

use crate::environment::EnvironmentMap;
use crate::output::ToneMap;
use crate::render::{Camera, Model, RenderOptions};
use crate::transfer::TransferFunctions;
use crate::volume::Volume;

#[derive(Clone, Debug)]
pub struct Scene {
    /// Short name for messages and the window title (e.g. "shell").
    pub name: String,
    pub volume: Volume,
    pub tf: TransferFunctions,
    /// Environment behind the volume (refractive model); None = the flat background.
    pub env: Option<EnvironmentMap>,
    pub model: Model,
    pub camera: Camera,
    /// Image size, sampling, light, specular, clipping (the viewer replaces the size with
    /// the window's).
    pub opts: RenderOptions,
    /// How linear colour becomes 8-bit output (PNG, the window).
    pub tone: ToneMap,
    /// Files the scene was read from (a transfer-function file, an environment map): the
    /// viewer reloads the scene when one of them changes.
    pub files: Vec<PathBuf>,
}

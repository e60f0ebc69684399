//! refrakt: interactive volume rendering with refraction, caustics, soft shadows and tinted
//! transmissive media, after Magnus & Bruckner, *Interactive Dynamic Volume Illumination
//! with Refraction and Caustics* (thesis, Univ. of Bergen; IEEE TVCG 2018).

pub mod vk;

/// SPIR-V of every shader in `glsl/`, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

pub mod bench;
pub mod camera;
pub mod environment;
pub mod files;
pub mod labels;
pub mod light;
pub mod output;
pub mod photons;
pub mod render;
pub mod scene;
pub mod tone;
pub mod transfer;
pub mod viewer;
pub mod volume;
pub mod workers;

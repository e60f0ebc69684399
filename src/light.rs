//! The directional light: plain data (no GPU types). Scenes without a light direction get
//! [`default_light`] for their camera; [`Light::default`] is the renderer's own default
//! (tests and library users that set no scene).

use glam::Vec3;

use crate::camera::Camera;

/// One directional light (thesis sect. 4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// World-space direction pointing towards the light (where the light comes from).
    pub towards: Vec3,
    /// Linear RGB.
    pub colour: [f32; 3],
    /// Size of the elliptical filter applied to the light at every plane, in reference
    /// steps (smallest voxel sides): 0 = one tap, hard shadows; larger = softer shadows
    /// and caustics (the light source's apparent size).
    pub softness: f32,
}

impl Default for Light {
    fn default() -> Self {
        Self {
            towards: Vec3::new(-0.3, 0.6, 1.0).normalize(),
            colour: [1.0, 1.0, 1.0],
            softness: 0.5,
        }
    }
}

/// Light from above, tilted towards the camera so the front-to-back sweep can carry it;
/// when the camera looks up too steeply for that, a key light from its upper left.
pub fn default_light(camera: &Camera) -> Vec3 {
    let (_, forward, right, up) = camera.frame();
    let above = (Vec3::Y - 0.5 * forward).normalize();
    if above.dot(-forward) >= 0.3 {
        above
    } else {
        (-forward + 0.6 * up - 0.4 * right).normalize()
    }
}

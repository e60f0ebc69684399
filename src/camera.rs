//! The orbit camera: plain data (no GPU types), shared by scenes, the renderer, the viewer
//! and the photon tracer.

use anyhow::{ensure, Result};
use glam::Vec3;

/// Orbit camera around a target point (by default the volume centre, the world origin).
/// The volume box's largest side is 1 world unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Degrees around the vertical (y) axis; 0 looks along -z from +z.
    pub azimuth: f32,
    /// Degrees above the horizontal plane, -90 to 90: 90 looks straight down, -90 straight
    /// up.
    pub elevation: f32,
    /// Distance from the target in world units.
    pub distance: f32,
    /// Vertical field of view in degrees.
    pub fov_y: f32,
    /// The world-space point the camera orbits and looks at (default: the origin).
    pub target: Vec3,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            azimuth: 30.0,
            elevation: 20.0,
            distance: 2.2,
            fov_y: 35.0,
            target: Vec3::ZERO,
        }
    }
}

impl Camera {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.azimuth.is_finite() && self.elevation.is_finite(),
            "camera angles must be finite numbers"
        );
        ensure!(
            self.elevation.abs() <= 90.0,
            "camera elevation {} must be between -90 and 90 degrees",
            self.elevation
        );
        ensure!(
            self.distance.is_finite() && self.distance > 0.0,
            "camera distance {} must be a positive number",
            self.distance
        );
        ensure!(
            self.fov_y.is_finite() && self.fov_y > 0.0 && self.fov_y < 180.0,
            "field of view {} must be strictly between 0 and 180 degrees",
            self.fov_y
        );
        ensure!(
            self.target.is_finite(),
            "camera target {} must be finite numbers",
            self.target
        );
        Ok(())
    }

    /// The eye relative to the target: `distance` along the direction given by azimuth
    /// and elevation. At exactly ±90° it is straight above (below) the target; the general
    /// formula would put it a hair past the pole there, as 90° in radians rounds above π/2.
    fn offset(&self) -> Vec3 {
        if self.elevation.abs() >= 90.0 {
            return self.distance * Vec3::new(0.0, self.elevation.signum(), 0.0);
        }
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        self.distance * Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos())
    }

    /// The eye in world space: `target` plus `distance` along the azimuth and elevation.
    pub fn eye(&self) -> Vec3 {
        self.target + self.offset()
    }

    /// (eye, forward, right, up), an orthonormal frame looking at `target`, with
    /// `up = right × forward`.
    ///
    /// Below ±90° elevation `right` is `forward × world Y` normalized, which is
    /// `(cos az, 0, -sin az)` whatever the elevation. Straight down or up (elevation ±90°,
    /// where that cross product vanishes) `right` is that same vector, so the frame is the
    /// limit of the one just below the pole and continuous in the elevation: looking
    /// straight down, screen-up is the horizontal direction the camera faced at this
    /// azimuth, `-(sin az, 0, cos az)`; looking straight up it is `(sin az, 0, cos az)`.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3, Vec3) {
        let offset = self.offset();
        let eye = self.target + offset;
        let forward = (-offset).normalize();
        let right = if self.elevation.abs() < 90.0 {
            forward.cross(Vec3::Y).normalize()
        } else {
            let az = self.azimuth.to_radians();
            Vec3::new(az.cos(), 0.0, -az.sin())
        };
        let up = right.cross(forward);
        (eye, forward, right, up)
    }
}

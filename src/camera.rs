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

/// The farthest the camera and its target may be from the volume's centre, world units
/// (the volume's box is 1 across).
pub const MAX_DISTANCE: f32 = 1000.0;

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
        // The volume's box is 1 across (world units): beyond a thousand boxes away, f32
        // depths are too coarse for the planes (and 1e20 overflowed into NaN directions).
        ensure!(
            self.distance.is_finite() && self.distance > 0.0 && self.distance <= MAX_DISTANCE,
            "camera distance {} must be a positive number up to {MAX_DISTANCE} (the volume's \
             box is 1 across)",
            self.distance
        );
        ensure!(
            self.fov_y.is_finite() && self.fov_y > 0.0 && self.fov_y < 180.0,
            "field of view {} must be strictly between 0 and 180 degrees",
            self.fov_y
        );
        ensure!(
            self.target.is_finite() && self.target.abs().max_element() <= MAX_DISTANCE,
            "camera target {} must be finite numbers within {MAX_DISTANCE} of the volume's \
             centre",
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(azimuth: f32, elevation: f32, target: Vec3) -> Camera {
        Camera {
            azimuth,
            elevation,
            distance: 2.0,
            fov_y: 35.0,
            target,
        }
    }

    /// Screen position of `p` in units of the half field of view (0, 0 = image centre).
    fn project(c: &Camera, p: Vec3) -> (f32, f32) {
        let (eye, forward, right, up) = c.frame();
        let v = p - eye;
        let z = v.dot(forward);
        assert!(z > 0.0, "{p} is behind the camera");
        let t = (c.fov_y.to_radians() * 0.5).tan();
        (v.dot(right) / (z * t), v.dot(up) / (z * t))
    }

    fn assert_orthonormal_right_handed(c: &Camera) {
        let (_, f, r, u) = c.frame();
        for (n, v) in [("forward", f), ("right", r), ("up", u)] {
            assert!((v.length() - 1.0).abs() < 1e-6, "{n} {v} of {c:?}");
        }
        assert!(f.dot(r).abs() < 1e-6 && f.dot(u).abs() < 1e-6 && r.dot(u).abs() < 1e-6);
        assert!((r.cross(f) - u).length() < 1e-6, "{c:?}");
    }

    #[test]
    fn the_camera_orbits_and_looks_at_its_target() {
        let t = Vec3::new(0.3, -0.2, 0.1);
        let c = cam(40.0, 25.0, t);
        let (eye, forward, ..) = c.frame();
        assert!(((eye - t).length() - 2.0).abs() < 1e-5);
        assert!((forward - (t - eye).normalize()).length() < 1e-6);
        // Same orientation as the camera around the origin, translated by the target.
        let o = cam(40.0, 25.0, Vec3::ZERO);
        assert_eq!(c.frame().1, o.frame().1);
        assert!((eye - (o.eye() + t)).length() < 1e-6);
        let (x, y) = project(&c, t);
        assert!(x.abs() < 1e-6 && y.abs() < 1e-6);
        assert!(c.validate().is_ok());
        assert!(cam(0.0, 0.0, Vec3::new(f32::NAN, 0.0, 0.0))
            .validate()
            .is_err());
        assert!(cam(0.0, 0.0, Vec3::new(0.0, f32::INFINITY, 0.0))
            .validate()
            .is_err());
    }

    #[test]
    fn straight_down_and_up_views_have_a_continuous_frame() {
        let t = Vec3::new(0.1, 0.2, -0.3);
        for az in [0.0f32, 30.0, 135.0, -100.0] {
            let down = cam(az, 90.0, t);
            assert!(down.validate().is_ok());
            assert_orthonormal_right_handed(&down);
            let (eye, forward, _, up) = down.frame();
            assert_eq!(forward, Vec3::new(0.0, -1.0, 0.0));
            assert!((eye - (t + Vec3::new(0.0, 2.0, 0.0))).length() < 1e-6);
            // Screen-up is the horizontal direction the camera faced at this azimuth.
            let a = az.to_radians();
            assert!((up + Vec3::new(a.sin(), 0.0, a.cos())).length() < 1e-6);
            // A point below the target is in the middle of the image.
            let (x, y) = project(&down, t - Vec3::new(0.0, 0.7, 0.0));
            assert!(x.abs() < 1e-6 && y.abs() < 1e-6, "{x} {y}");
            let up_cam = cam(az, -90.0, t);
            assert_orthonormal_right_handed(&up_cam);
            assert_eq!(up_cam.frame().1, Vec3::Y);
            // Continuity at the poles: just below is nearly the same frame.
            for (pole, near) in [(down, cam(az, 89.999, t)), (up_cam, cam(az, -89.999, t))] {
                assert_orthonormal_right_handed(&near);
                let (a, b) = (pole.frame(), near.frame());
                for (p, q) in [(a.0, b.0), (a.1, b.1), (a.2, b.2), (a.3, b.3)] {
                    assert!((p - q).length() < 1e-4, "{p} vs {q} at azimuth {az}");
                }
            }
        }
        assert!(cam(0.0, 90.01, Vec3::ZERO).validate().is_err());
        assert!(cam(0.0, -90.01, Vec3::ZERO).validate().is_err());
    }

    #[test]
    fn frames_below_the_poles_are_unchanged() {
        // The formula every image so far was rendered with.
        for (az, el) in [
            (30.0f32, 20.0f32),
            (-45.0, 0.0),
            (200.0, -89.9),
            (10.0, 89.99),
        ] {
            let c = cam(az, el, Vec3::ZERO);
            let (a, e) = (az.to_radians(), el.to_radians());
            let eye = 2.0 * Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos());
            let forward = (-eye).normalize();
            let right = forward.cross(Vec3::Y).normalize();
            let up = right.cross(forward);
            assert_eq!(c.frame(), (eye, forward, right, up));
            assert_orthonormal_right_handed(&c);
        }
    }
}

//! The directional light: plain data (no GPU types), with ONE default: white, softness
//! [`Light::DEFAULT_SOFTNESS`], from [`default_light`] for the camera it lights
//! ([`Light::for_camera`]). Scenes without a light direction and the renderer's own
//! default options (for the default camera) both use it.

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

impl Light {
    pub const DEFAULT_COLOUR: [f32; 3] = [1.0; 3];
    pub const DEFAULT_SOFTNESS: f32 = 0.5;

    /// The default light for `camera`: white, default softness, from [`default_light`].
    pub fn for_camera(camera: &Camera) -> Self {
        Self {
            towards: default_light(camera),
            colour: Self::DEFAULT_COLOUR,
            softness: Self::DEFAULT_SOFTNESS,
        }
    }
}

/// Where a light of the ambient-scattering model shines from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// Parallel light from the world-space direction `towards` (need not be unit).
    Directional { towards: Vec3 },
    /// Light from a point in world space (the volume's box is centred at the origin).
    Point { position: Vec3 },
}

/// A light beside the main one ([`Light`]), for the models that take several (ambient
/// scattering): its source and linear RGB colour (a point light's: the irradiance at unit
/// distance; it falls off with the squared distance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtraLight {
    pub source: LightSource,
    pub colour: [f32; 3],
}

impl ExtraLight {
    pub fn validate(&self) -> anyhow::Result<()> {
        let v = match self.source {
            LightSource::Directional { towards } => {
                anyhow::ensure!(
                    towards.is_finite() && towards.length() > 1e-6,
                    "a directional light needs a finite, non-zero direction, got {towards}"
                );
                towards
            }
            LightSource::Point { position } => position,
        };
        anyhow::ensure!(v.is_finite(), "light position {v} is not finite");
        anyhow::ensure!(
            self.colour.iter().all(|c| c.is_finite() && *c >= 0.0),
            "light colour {:?} must be finite and non-negative",
            self.colour
        );
        Ok(())
    }
}

impl std::str::FromStr for ExtraLight {
    type Err = anyhow::Error;

    /// `dir:X,Y,Z` (towards the light) or `point:X,Y,Z` (world position), optionally
    /// followed by `@R,G,B` (linear colour; white without it).
    fn from_str(text: &str) -> anyhow::Result<Self> {
        let triple = |t: &str, what: &str| -> anyhow::Result<Vec3> {
            let v: Vec<f32> = t
                .split(',')
                .map(|c| c.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|e| anyhow::anyhow!("light '{text}': {what} '{t}': {e}"))?;
            anyhow::ensure!(
                v.len() == 3,
                "light '{text}': {what} needs three comma-separated numbers, got '{t}'"
            );
            Ok(Vec3::new(v[0], v[1], v[2]))
        };
        let (kind, rest) = text.split_once(':').ok_or_else(|| {
            anyhow::anyhow!("light '{text}' must be dir:X,Y,Z or point:X,Y,Z (then @R,G,B)")
        })?;
        let (at, colour) = match rest.split_once('@') {
            Some((a, c)) => (a, triple(c, "colour")?.to_array()),
            None => (rest, [1.0; 3]),
        };
        let source = match kind.trim() {
            "dir" | "directional" => LightSource::Directional {
                towards: triple(at, "direction")?,
            },
            "point" => LightSource::Point {
                position: triple(at, "position")?,
            },
            other => anyhow::bail!("light '{text}': unknown kind '{other}' (dir or point)"),
        };
        let l = Self { source, colour };
        l.validate()?;
        Ok(l)
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

/// Largest angle between the light and the direction back to the camera that the viewer's
/// controls allow: 4.3° inside the sweep's limit (acos MIN_FORWARD ≈ 84.3°), so a light
/// turned to the edge still renders (a test keeps it inside).
pub const MAX_LIGHT_ANGLE_DEG: f32 = 80.0;
/// `towards` (a direction to the light), moved into the cone of [`MAX_LIGHT_ANGLE_DEG`]
/// around the direction from the volume to the camera if it is outside, keeping its
/// azimuth about that axis.
pub fn clamp_light(towards: Vec3, camera: &Camera) -> Vec3 {
    let (_, forward, _, up) = camera.frame();
    let back = -forward;
    let t = towards.normalize_or(back);
    let max = MAX_LIGHT_ANGLE_DEG.to_radians();
    if t.dot(back) >= max.cos() {
        return t;
    }
    let side = (t - t.dot(back) * back).normalize_or(up);
    (max.cos() * back + max.sin() * side).normalize()
}

/// The light turned by `yaw` (to the viewer's right) and `pitch` (up) degrees in the
/// camera's frame, then clamped with [`clamp_light`].
pub fn turn_light(towards: Vec3, camera: &Camera, yaw: f32, pitch: f32) -> Vec3 {
    let (_, forward, right, up) = camera.frame();
    let back = -forward;
    let t = clamp_light(towards, camera);
    let (x, y, z) = (t.dot(right), t.dot(up), t.dot(back));
    let az = x.atan2(z) + yaw.to_radians();
    let el = (y.clamp(-1.0, 1.0).asin() + pitch.to_radians()).clamp(
        -MAX_LIGHT_ANGLE_DEG.to_radians(),
        MAX_LIGHT_ANGLE_DEG.to_radians(),
    );
    let l = el.cos() * az.sin() * right + el.sin() * up + el.cos() * az.cos() * back;
    clamp_light(l, camera)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angle_to_camera(t: Vec3, c: &Camera) -> f32 {
        let (_, forward, _, _) = c.frame();
        t.normalize()
            .dot(-forward)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    #[test]
    fn the_viewers_cone_is_inside_the_sweeps_limit() {
        let limit = crate::render::limits::MIN_FORWARD.acos().to_degrees();
        assert!(
            MAX_LIGHT_ANGLE_DEG < limit - 1.0,
            "{MAX_LIGHT_ANGLE_DEG} vs {limit}"
        );
    }

    #[test]
    fn extra_lights_parse_and_refuse_nonsense() {
        let l: ExtraLight = "point:0.5,1,-2@2,1,0.5".parse().unwrap();
        assert_eq!(
            l.source,
            LightSource::Point {
                position: Vec3::new(0.5, 1.0, -2.0)
            }
        );
        assert_eq!(l.colour, [2.0, 1.0, 0.5]);
        let d: ExtraLight = "dir:0,1,0".parse().unwrap();
        assert_eq!(d.colour, [1.0; 3]);
        for bad in [
            "0,1,0",
            "dir:0,0,0",
            "spot:0,1,0",
            "dir:0,1",
            "point:0,1,x",
            "dir:0,1,0@-1,0,0",
        ] {
            assert!(bad.parse::<ExtraLight>().is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn light_is_kept_in_the_viewers_cone() {
        let c = Camera::default();
        let (_, forward, right, _) = c.frame();
        // From behind the volume: clamped to the cone's edge, on the same side.
        let behind = (forward + 0.3 * right).normalize();
        let l = clamp_light(behind, &c);
        assert!((angle_to_camera(l, &c) - MAX_LIGHT_ANGLE_DEG).abs() < 0.01);
        assert!(l.dot(right) > 0.0);
        // Inside: unchanged.
        let inside = (-forward + 0.2 * right).normalize();
        assert!((clamp_light(inside, &c) - inside).length() < 1e-6);
    }

    #[test]
    fn turning_the_light_moves_it_and_stays_in_the_cone() {
        let c = Camera::default();
        let (_, forward, right, up) = c.frame();
        let l0 = -forward;
        let l1 = turn_light(l0, &c, 20.0, 0.0);
        assert!(l1.dot(right) > 0.3, "yaw right moves the light right");
        let l2 = turn_light(l0, &c, 0.0, 20.0);
        assert!(l2.dot(up) > 0.3, "pitch up moves the light up");
        let mut l = l0;
        for _ in 0..100 {
            l = turn_light(l, &c, 7.0, 3.0);
            assert!(angle_to_camera(l, &c) <= MAX_LIGHT_ANGLE_DEG + 0.01);
        }
    }
}

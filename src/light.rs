//! The lights: plain data (no GPU types). One type for every model ([`Light`]: a
//! directional or point source, a colour and a softness), held by the render options as a
//! list whose first entry is the main light ([`crate::render::RenderOptions::lights`]).
//! Each model says how many it takes and whether point lights are among them
//! ([`crate::render::Model::light_support`]). ONE default: white, softness
//! [`Light::DEFAULT_SOFTNESS`], from [`default_light`] for the camera it lights
//! ([`Light::for_camera`]). Scenes without a light and the renderer's own default options
//! (for the default camera) both use it.

use anyhow::Context;
use glam::Vec3;

use crate::camera::Camera;

/// Where a light shines from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// Parallel light from the world-space direction `towards` (need not be unit): the
    /// thesis' light (sect. 4.2).
    Directional { towards: Vec3 },
    /// Light from a point in world space (the volume's box is centred at the origin); its
    /// colour is the irradiance at unit distance, falling off with the squared distance.
    Point { position: Vec3 },
}

/// One light: its source, linear RGB colour and softness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub source: LightSource,
    /// Linear RGB.
    pub colour: [f32; 3],
    /// Size of the elliptical filter applied to the light at every plane, in reference
    /// steps (smallest voxel sides): 0 = one tap, hard shadows; larger = softer shadows
    /// and caustics (the light source's apparent size). The sweep's; the ray-marched
    /// models' lights are hard.
    pub softness: f32,
}

impl Light {
    pub const DEFAULT_COLOUR: [f32; 3] = [1.0; 3];
    pub const DEFAULT_SOFTNESS: f32 = 0.5;

    /// A directional light towards `towards`, with the default softness.
    pub fn directional(towards: Vec3, colour: [f32; 3]) -> Self {
        Self {
            source: LightSource::Directional { towards },
            colour,
            softness: Self::DEFAULT_SOFTNESS,
        }
    }

    /// The default light for `camera`: white, default softness, from [`default_light`].
    pub fn for_camera(camera: &Camera) -> Self {
        Self::directional(default_light(camera), Self::DEFAULT_COLOUR)
    }

    /// Towards the light from the volume's centre (the world origin): a directional
    /// light's direction, a point light's position. Not normalised.
    pub fn towards(&self) -> Vec3 {
        match self.source {
            LightSource::Directional { towards } => towards,
            LightSource::Point { position } => position,
        }
    }

    /// The unit direction the light travels from the volume's centre on: −towards,
    /// normalised (the sweep's, whose light is directional; thesis sect. 4.2).
    pub fn travel(&self) -> Vec3 {
        -self.towards().normalize()
    }

    /// Make this a directional light towards `towards` (colour and softness kept).
    pub fn set_towards(&mut self, towards: Vec3) {
        self.source = LightSource::Directional { towards };
    }

    pub fn is_point(&self) -> bool {
        matches!(self.source, LightSource::Point { .. })
    }

    /// "directional light towards (x, y, z)" or "point light at (x, y, z)", for errors.
    pub fn describe(&self) -> String {
        match self.source {
            LightSource::Directional { towards: t } => {
                format!("directional light towards ({}, {}, {})", t.x, t.y, t.z)
            }
            LightSource::Point { position: p } => {
                format!("point light at ({}, {}, {})", p.x, p.y, p.z)
            }
        }
    }

    pub fn validate(&self) -> anyhow::Result<()> {
        let v = match self.source {
            LightSource::Directional { towards } => {
                anyhow::ensure!(
                    towards.is_finite() && towards.length() > 1e-6,
                    "light direction {towards} must be a finite, non-zero vector (towards a \
                     directional light)"
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
        anyhow::ensure!(
            self.softness.is_finite() && (0.0..=8.0).contains(&self.softness),
            "light softness {} must be in [0, 8] (filter radius in voxels)",
            self.softness
        );
        Ok(())
    }
}

impl LightSource {
    /// A directional light towards `towards`, as given, at any finite length: only its
    /// direction counts. One whose length overflows or underflows f32 (1e20,1e20,0 was
    /// judged 90° from the view, 1e-20,1e-20,0 zero) is rescaled so its largest component
    /// is ±1; any other is kept as given.
    pub fn directional(towards: Vec3) -> Self {
        let (l, m) = (towards.length(), towards.abs().max_element());
        let towards = if !(l.is_finite() && l > 1e-6) && m.is_finite() && m > 0.0 {
            towards / m
        } else {
            towards
        };
        LightSource::Directional { towards }
    }

    /// `X,Y,Z` or `dir:X,Y,Z` (towards the light), or `point:X,Y,Z` (world position),
    /// optionally followed by `@R,G,B` (linear colour): the source and the colour if given.
    pub fn parse_with_colour(text: &str) -> anyhow::Result<(Self, Option<[f32; 3]>)> {
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
        let (kind, rest) = match text.split_once(':') {
            Some((k, r)) => (k.trim(), r),
            None => ("dir", text),
        };
        let (at, colour) = match rest.split_once('@') {
            Some((a, c)) => (a, Some(triple(c, "colour")?.to_array())),
            None => (rest, None),
        };
        let source = match kind {
            "dir" | "directional" => LightSource::directional(triple(at, "direction")?),
            "point" => LightSource::Point {
                position: triple(at, "position")?,
            },
            other => anyhow::bail!(
                "light '{text}': unknown kind '{other}' (X,Y,Z, dir:X,Y,Z or point:X,Y,Z, \
                 then @R,G,B)"
            ),
        };
        Ok((source, colour))
    }
}

impl std::str::FromStr for Light {
    type Err = anyhow::Error;

    /// As [`LightSource::parse_with_colour`]; white without a colour, the default softness.
    fn from_str(text: &str) -> anyhow::Result<Self> {
        let (source, colour) = LightSource::parse_with_colour(text)?;
        let l = Self {
            source,
            colour: colour.unwrap_or(Self::DEFAULT_COLOUR),
            softness: Self::DEFAULT_SOFTNESS,
        };
        l.validate().with_context(|| format!("light '{text}'"))?;
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
    fn lights_parse_and_refuse_nonsense() {
        let l: Light = "point:0.5,1,-2@2,1,0.5".parse().unwrap();
        assert_eq!(
            l.source,
            LightSource::Point {
                position: Vec3::new(0.5, 1.0, -2.0)
            }
        );
        assert_eq!(l.colour, [2.0, 1.0, 0.5]);
        let d: Light = "dir:0,1,0".parse().unwrap();
        assert_eq!(d.colour, [1.0; 3]);
        // A bare direction is a directional light, as `--light X,Y,Z` always was.
        let bare: Light = "0,2,1@0.5,0.5,0.5".parse().unwrap();
        assert_eq!(
            bare.source,
            LightSource::Directional {
                towards: Vec3::new(0.0, 2.0, 1.0)
            }
        );
        assert_eq!(bare.colour, [0.5; 3]);
        for bad in [
            "0,1",
            "dir:0,0,0",
            "spot:0,1,0",
            "dir:0,1",
            "point:0,1,x",
            "dir:0,1,0@-1,0,0",
        ] {
            assert!(bad.parse::<Light>().is_err(), "{bad} accepted");
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

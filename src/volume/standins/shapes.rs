//! The stand-ins' shapes: one function per data set, the value at a point of the unit
//! box (and the voxel size, for the one-voxel ramps of the surfaces), built from signed
//! distances, seeded noise and the procedural shells.

use glam::Vec3;

use crate::volume::procedural::{fbm, shell_value};

/// Smooth inside indicator of a signed distance (positive inside): a ramp about one voxel
/// wide, so that trilinear reconstruction keeps the surface where the distance is 0 and
/// refraction through it is not noisy (docs/NOTES.md, refraction geometry).
pub(super) fn inside(d: f32, voxel: f32) -> f32 {
    0.5 + 0.5 * (d / voxel).tanh()
}

/// Signed distance (positive inside) of an ellipsoid, approximate away from the surface.
fn ellipsoid(p: Vec3, c: Vec3, r: Vec3) -> f32 {
    let q = (p - c) / r;
    (1.0 - q.length()) * r.min_element()
}

/// Signed distance (positive inside) of a capsule from a to b with radius r.
fn capsule(p: Vec3, a: Vec3, b: Vec3, r: f32) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    r - (p - (a + t * ab)).length()
}

fn noise(p: Vec3, scale: f32, seed: u32) -> f32 {
    fbm((p * scale).to_array(), seed)
}

// Values of the stand-ins are chosen for their transfer-function presets (assets/tf/):
// the comments there say which value is which material.

pub(super) fn supernova(p: Vec3, voxel: f32) -> f32 {
    let floor = inside(-0.42 - p.y, voxel);
    let shell = 0.8 * shell_value([p.x, p.y + 0.04, p.z], 7);
    shell.max(floor)
}

pub(super) fn piggy_bank(p: Vec3, voxel: f32) -> f32 {
    // Box coordinates: x, y in [-0.5, 0.5], z in ±0.13. The body is an ellipsoid lying in
    // the volume, a ceramic shell 2.5 voxels thick, with a snout, ears, legs and a coin slot.
    let c = Vec3::ZERO;
    let r = Vec3::new(0.36, 0.25, 0.11);
    let body = ellipsoid(p, c, r);
    let snout = capsule(
        p,
        Vec3::new(0.33, 0.0, 0.0),
        Vec3::new(0.42, 0.0, 0.0),
        0.07,
    );
    let ear = capsule(
        p,
        Vec3::new(0.2, 0.2, 0.0),
        Vec3::new(0.24, 0.3, 0.0),
        0.035,
    )
    .max(capsule(
        p,
        Vec3::new(0.1, 0.22, 0.0),
        Vec3::new(0.1, 0.32, 0.0),
        0.035,
    ));
    let legs = [-0.2f32, 0.15]
        .iter()
        .map(|&x| capsule(p, Vec3::new(x, -0.2, 0.0), Vec3::new(x, -0.33, 0.0), 0.05))
        .fold(f32::NEG_INFINITY, f32::max);
    let solid = body.max(snout).max(ear).max(legs);
    let t = 2.5 * voxel;
    let slot = (0.012 - p.x.abs()).min(0.05 - (p.y - 0.24).abs());
    let shell = solid.min(t - solid).min(-slot);
    let coin = (0.05 - (p - Vec3::new(-0.05, -0.19, 0.0)).length()).min(0.012 - p.z.abs());
    (0.6 * inside(shell, voxel)).max(0.9 * inside(coin, voxel))
}

/// The glass as a solid of revolution about y, on a floor before a back wall.
pub(super) fn glass(p: Vec3, voxel: f32) -> f32 {
    let radial = (p.x * p.x + p.z * p.z).sqrt();
    let c = Vec3::new(0.0, 0.08, 0.0);
    let r = (p - c).length();
    let (r_in, r_out) = (0.21, 0.23);
    let rim = c.y + 0.15;
    let bowl = (r_out - r).min(r - r_in).min(rim - p.y);
    let stem = (0.02 - radial)
        .min(c.y - r_out + 0.01 - p.y)
        .min(p.y + 0.33);
    let foot = (0.15 - radial).min(0.012 - (p.y + 0.34).abs());
    let glass = inside(bowl.max(stem).max(foot), voxel);
    let liquid = inside((r_in - r).min(c.y + 0.03 - p.y), voxel);
    let floor = inside(-0.36 - p.y, voxel);
    let wall = inside(-0.42 - p.z, voxel);
    (0.4 * glass).max(0.8 * liquid).max(floor.max(wall))
}

pub(super) fn hand(p: Vec3, voxel: f32) -> f32 {
    // Box: x ±0.47 (width), y ±0.24 (thickness), z ±0.5 (length, fingers towards -z).
    let palm_c = Vec3::new(0.0, 0.0, 0.17);
    let palm = ellipsoid(p, palm_c, Vec3::new(0.3, 0.11, 0.26));
    let mut tissue = palm;
    let mut bone = f32::NEG_INFINITY;
    let mut vessel = f32::NEG_INFINITY;
    let fingers = [
        (-0.21, 0.28, 0.06),
        (-0.07, 0.34, 0.055),
        (0.07, 0.32, 0.055),
        (0.2, 0.26, 0.05),
    ];
    for (x, len, r) in fingers {
        let base = Vec3::new(x, 0.0, 0.0);
        let tip = Vec3::new(x * 1.15, -0.02, -len);
        tissue = tissue.max(capsule(p, base, tip, r));
        // Phalanges: three bones with joints.
        for k in 0..3 {
            let a = base.lerp(tip, k as f32 / 3.0 + 0.02);
            let b = base.lerp(tip, (k + 1) as f32 / 3.0 - 0.04);
            bone = bone.max(capsule(p, a, b, 0.45 * r));
        }
        // Metacarpal.
        bone = bone.max(capsule(
            p,
            Vec3::new(x * 0.6, 0.0, 0.36),
            Vec3::new(x, 0.0, 0.03),
            0.4 * r,
        ));
        // A digital artery on the palm side of each finger.
        vessel = vessel.max(capsule(
            p,
            Vec3::new(x * 0.7, -0.06, 0.3),
            tip + Vec3::new(0.0, -0.025, 0.03),
            0.012,
        ));
    }
    let thumb_base = Vec3::new(0.27, 0.0, 0.25);
    let thumb_tip = Vec3::new(0.44, -0.03, 0.0);
    tissue = tissue.max(capsule(p, thumb_base, thumb_tip, 0.065));
    bone = bone.max(capsule(p, thumb_base, thumb_tip, 0.028));
    // The palmar arch joining the arteries.
    vessel = vessel.max(capsule(
        p,
        Vec3::new(-0.2, -0.07, 0.3),
        Vec3::new(0.2, -0.07, 0.3),
        0.014,
    ));
    let texture = 0.04 * (noise(p, 24.0, 3) - 0.5);
    let t = inside(tissue, voxel) * (0.3 + texture);
    t.max(0.6 * inside(vessel, voxel))
        .max(0.9 * inside(bone, voxel))
}

pub(super) fn head(p: Vec3, voxel: f32) -> f32 {
    // Box: x, y ±0.5, z ±0.325 (front at +z). Skull, scalp and soft tissue, brain, air
    // cavities (sinuses, airway) and a jaw.
    let c = Vec3::new(0.0, 0.05, 0.0);
    let scalp = ellipsoid(p, c, Vec3::new(0.34, 0.4, 0.3));
    let skull_out = ellipsoid(p, c, Vec3::new(0.31, 0.37, 0.27));
    let skull_in = ellipsoid(p, c, Vec3::new(0.28, 0.34, 0.24));
    let skull = skull_out.min(-skull_in);
    let jaw = capsule(
        p,
        Vec3::new(-0.18, -0.28, 0.1),
        Vec3::new(0.18, -0.28, 0.1),
        0.035,
    )
    .max(capsule(
        p,
        Vec3::new(0.0, -0.3, 0.2),
        Vec3::new(0.0, -0.28, 0.22),
        0.04,
    ));
    let neck = capsule(
        p,
        Vec3::new(0.0, -0.2, -0.03),
        Vec3::new(0.0, -0.5, -0.05),
        0.14,
    );
    let tissue = scalp.max(neck);
    let sinus = ellipsoid(p, Vec3::new(-0.08, -0.12, 0.2), Vec3::new(0.06, 0.05, 0.05))
        .max(ellipsoid(
            p,
            Vec3::new(0.08, -0.12, 0.2),
            Vec3::new(0.06, 0.05, 0.05),
        ))
        .max(ellipsoid(
            p,
            Vec3::new(0.0, 0.02, 0.24),
            Vec3::new(0.05, 0.04, 0.025),
        ));
    let airway = capsule(
        p,
        Vec3::new(0.0, -0.16, 0.12),
        Vec3::new(0.0, -0.5, 0.0),
        0.03,
    );
    let air = sinus.max(airway);
    let brain = skull_in - 0.01;
    let folds = 0.05 * (noise(p, 30.0, 11) - 0.5);
    let soft = inside(tissue, voxel) * 0.35;
    let v = soft
        .max(inside(brain, voxel) * (0.45 + folds))
        .max(0.9 * inside(skull.max(jaw), voxel));
    v * (1.0 - inside(air, voxel))
}

pub(super) fn water(p: Vec3, voxel: f32) -> f32 {
    // Box: x, y ±0.5, z ±0.25. Water below a wavy surface, a sandy floor at the bottom.
    let waves = 0.025 * (p.x * 23.0 + 1.3).sin() * (p.z * 17.0).cos()
        + 0.012 * (p.x * 41.0 - p.z * 37.0).sin()
        + 0.02 * (noise(p, 9.0, 5) - 0.5);
    let surface = 0.12 + waves - p.y;
    let floor = -0.4 + 0.02 * (noise(p, 14.0, 9) - 0.5) - p.y;
    (0.5 * inside(surface, voxel)).max(inside(floor, voxel))
}

pub(super) fn ship(p: Vec3, voxel: f32) -> f32 {
    // Box: x, y ±0.33, z ±0.5. A refractive block filling most of it, a ship inside:
    // hull, deck house, two masts and sails.
    let block = (0.3 - p.x.abs()).min(0.3 - p.y.abs()).min(0.46 - p.z.abs());
    let hull_w = 0.1 * (1.0 - (p.z / 0.36).powi(2)).max(0.0).sqrt();
    let hull = (hull_w - p.x.abs())
        .min(p.y + 0.12)
        .min(-0.02 - p.y + 0.1 * (p.z / 0.36).powi(2))
        .min(0.36 - p.z.abs());
    let house = (0.05 - p.x.abs())
        .min(0.06 - (p.y - 0.0).abs())
        .min(0.08 - (p.z - 0.1).abs());
    let masts = capsule(
        p,
        Vec3::new(0.0, -0.02, -0.12),
        Vec3::new(0.0, 0.26, -0.12),
        0.008,
    )
    .max(capsule(
        p,
        Vec3::new(0.0, -0.02, 0.02),
        Vec3::new(0.0, 0.22, 0.02),
        0.008,
    ));
    let sails = (0.004 - (p.x - 0.012).abs())
        .min(0.1 - (p.z + 0.12).abs())
        .min(0.1 - (p.y - 0.14).abs())
        .max(
            (0.004 - (p.x - 0.012).abs())
                .min(0.08 - (p.z - 0.02).abs())
                .min(0.08 - (p.y - 0.12).abs()),
        );
    let ship = hull.max(house).max(masts).max(sails);
    (0.3 * inside(block, voxel)).max(0.85 * inside(ship, voxel))
}

pub(super) fn kiwi(p: Vec3, voxel: f32) -> f32 {
    // Box: x, y ±0.5, z ±0.25. A slice of kiwifruit facing ±z: an elliptical disc with
    // skin, green flesh with radial texture, a ring of dark seeds and a pale core.
    let q = Vec3::new(p.x / 0.42, p.y / 0.36, 0.0);
    let rho = q.length();
    let slice = (1.0 - rho).min(0.12 - p.z.abs()) * 0.36;
    let angle = q.y.atan2(q.x);
    let rays = 0.5 + 0.5 * (angle * 36.0).cos();
    let flesh = 0.4 + 0.05 * rays * (rho - 0.25).clamp(0.0, 1.0);
    let skin = inside(slice, voxel) - inside(slice - 1.5 * voxel, voxel);
    // Seeds: small ellipsoids on a ring at rho ≈ 0.38, 40 of them.
    let k = (angle / std::f32::consts::TAU * 40.0).round();
    let a = k / 40.0 * std::f32::consts::TAU;
    let seed_c = Vec3::new(0.42 * 0.38 * a.cos(), 0.36 * 0.38 * a.sin(), 0.0);
    let seed = 0.012 - ((p - seed_c) * Vec3::new(1.0, 1.0, 0.5)).length();
    let core = 0.24 - rho;
    let v = inside(slice, voxel) * if core > 0.0 { 0.6 } else { flesh };
    v.max(0.75 * skin).max(0.95 * inside(seed, voxel))
}

//! The reference renderer (issue 32 item 5): whole camera images of the refractive model,
//! on the CPU, from the photon tracer's field and integrator, so that a renderer's image
//! can be compared with one made without any of its approximations.
//!
//! # What it computes
//!
//! 1. **The light**, as a fluence volume. Photons are launched on a plane normal to each
//!    directional light, a regular grid of k × k per voxel side covering the box, each carrying the light's colour × its launch cell's area, and
//!    traced with the photon tracer's RK4 through η, attenuated by the opacity and the
//!    medium as it attenuates them ([`Field::trace`]). Each photon deposits its flux ×
//!    the length of its path into bins (`light_bins` per voxel side; a track-length
//!    estimator, each piece of path shared among the 8 bins around it with trilinear
//!    weights): fluence = Σ flux · length · weight / bin volume, so light that nothing
//!    obstructs reads exactly the light's colour (flux per unit area normal to the light,
//!    as the eikonal model's light volume holds it) and a focus reads its flux density
//!    without any assumption on the wavefront. The viewing rays read it trilinearly
//!    between the bins' centres. Light from any direction, several lights (their fluence
//!    adds). Why a regular grid and the trilinear share: the bins' fluence from uniform
//!    light is the launch grid's sum of the kernel's projection along the light; its
//!    error lies at the grid's frequencies, where the trilinear kernel's spectrum (sinc²
//!    per axis) has all but vanished (measured: 0.03-0.06 % in the lit slab test,
//!    oblique light included; jittered photons, or box bins (sinc), left 2-12 % noise
//!    per pixel there). The light is not Fresnel-split (as the sweep's and the photon tracer's are
//!    not): it passes every face whole.
//! 2. **The view.** One ray per pixel (or k × k, `rays_per_pixel`) from the eye through
//!    the pixel (the GPU's `camera_ray`), integrated with the same RK4 in (x, v = η dx/ds)
//!    at `step` voxels, straight through bricks where η is constant (their matter
//!    composited at the same step). Each piece of path (length ℓ, at its midpoint: colour
//!    c, extinction σ = −ln(1 − α) / ref_step, the medium's rate μ = −ln m / ref_step) is
//!    composited front to back in the sweep's image formation (eq. 4.13, Oddy–Willis):
//!
//!    C += (1 − A) M c a (L + ambient),  A += (1 − A) a,  M *= e^(−μ ℓ),  a = 1 − e^(−σ ℓ),
//!
//!    with L the fluence at the midpoint (1 for `unlit`). Where it leaves the box it sees
//!    the environment map in its bent direction (one bilinear lookup, the GPU's
//!    conventions and rotation) or the background, through (1 − A) M.
//! 3. **Faces reflect (Fresnel).** A face is where η steps between two plateaus: where a
//!    piece of path passes η's middle between the plateaus found 2.5 voxels (plus half the
//!    piece) either side along ∇η, the plateaus differ by [`MIN_FACE_STEP`] or more, and
//!    half-way out η is already on either side of the middle (not a film).
//!    There the ray splits: the fraction F (unpolarised Fresnel between the plateaus, at
//!    the angle of the tangential part of v, which crossing the face keeps) is traced on
//!    as a new ray in the mirrored direction, **through the volume** (it sees the floor a
//!    glass stands on, up to `bounces` reflections deep), and the ray goes on through
//!    the face with the rest (F folded into A, as the sweep does). Beyond the critical
//!    angle nothing splits: the ray equation turns the ray itself back. Films (η rising
//!    and falling back within the probes, as on the glass floor's skin) are not faces
//!    here: what they reflect is left out.
//!
//! # What it leaves out, on purpose
//!
//! The specular highlight (a directional light is a delta; the sweep's GGX lobe is a
//! model of its own), the sweep's limits (light within 84° of the view, the gain bound)
//! and its layer model at surfaces: where the light changes within a voxel (a lit
//! surface's skin) the bins resolve it at their size, so the reference's light there
//! converges with `light_bins`, not with the sample distance.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use glam::DVec2;

use super::*;
use crate::environment::EnvironmentMap;

/// Smallest step of η between a face's plateaus that reflects (the sweep's threshold,
/// glsl/sweep_plane.glsl): below it the change is noise or a graded medium.
pub const MIN_FACE_STEP: f64 = 0.02;

/// How far either side of a piece of path the face's plateaus are probed, in voxels
/// (beyond half the piece).
const PLATEAU_PROBE: f64 = 2.5;

/// Options of the reference renderer.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    /// Photons per voxel side of the launch plane (k × k per voxel area).
    pub photons_per_voxel: u32,
    /// Bins of the light volume per voxel side.
    pub light_bins: u32,
    /// RK4 step of photons and viewing rays, in voxels.
    pub step: f32,
    /// Viewing rays per pixel side (k × k per pixel, averaged).
    pub rays_per_pixel: u32,
    /// Fresnel reflections traced at most this deep (0: none).
    pub bounces: u32,
    /// η from the cubic B-spline of the values instead of trilinear
    /// ([`Field::use_cubic_eta`]).
    pub cubic_eta: bool,
    /// Worker threads; 0 = all available.
    pub threads: usize,
    /// Refuse, before tracing, a job of more estimated RK4 steps than this (None: no limit).
    pub max_steps: Option<f64>,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        Self {
            photons_per_voxel: 8,
            light_bins: 2,
            step: 0.1,
            rays_per_pixel: 1,
            bounces: 3,
            cubic_eta: true,
            threads: 0,
            max_steps: None,
        }
    }
}

impl ReferenceOptions {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            (1..=64).contains(&self.photons_per_voxel),
            "photons per voxel side {} must be between 1 and 64",
            self.photons_per_voxel
        );
        ensure!(
            (1..=8).contains(&self.light_bins),
            "light bins per voxel side {} must be between 1 and 8",
            self.light_bins
        );
        ensure!(
            self.step.is_finite() && self.step > 0.0 && self.step <= 4.0,
            "step {} must be in (0, 4] voxels",
            self.step
        );
        ensure!(
            (1..=16).contains(&self.rays_per_pixel),
            "viewing rays per pixel side {} must be between 1 and 16",
            self.rays_per_pixel
        );
        ensure!(
            self.bounces <= 16,
            "reflections {} deep are more than 16",
            self.bounces
        );
        Ok(())
    }
}

/// A reference camera image and what making it took.
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first, linear RGBA (the layout of a rendered frame).
    pub pixels: Vec<[f32; 4]>,
    /// Photons traced (all lights).
    pub photons: u64,
    /// Bins of the light volume per axis.
    pub bins: [usize; 3],
    /// Viewing rays traced, the reflected ones included.
    pub rays: u64,
    /// Reflected rays among them.
    pub reflected: u64,
    pub light_seconds: f64,
    pub view_seconds: f64,
    pub threads: usize,
}

impl ReferenceImage {
    /// A few lines for the command line.
    pub fn summary(&self) -> String {
        format!(
            "light: {} photons into {}x{}x{} bins in {:.2} s\n\
             view: {} rays ({} of them reflections) in {:.2} s ({} threads)",
            self.photons,
            self.bins[0],
            self.bins[1],
            self.bins[2],
            self.light_seconds,
            self.rays,
            self.reflected,
            self.view_seconds,
            self.threads
        )
    }
}

/// The fluence of the lights on bins over the volume box.
struct LightBins {
    n: [usize; 3],
    /// Bin coordinate = world * scale + offset (bin i spans [i, i + 1)).
    scale: DVec3,
    offset: DVec3,
    fluence: Vec<[f32; 3]>,
}

impl LightBins {
    fn new(field: &Field, per_voxel: usize) -> Self {
        let n = field.dims.map(|d| d * per_voxel);
        let nd = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        let scale = nd / (2.0 * field.half);
        Self {
            n,
            scale,
            offset: 0.5 * nd,
            fluence: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// World volume of one bin.
    fn bin_volume(&self) -> f64 {
        1.0 / (self.scale.x * self.scale.y * self.scale.z)
    }

    /// The 8 bins around p and their trilinear (tent) weights, in bin-centre coordinates,
    /// indices clamped at the box's faces (so that near a face the weights still add up to
    /// 1: uniform light stays uniform up to the face). None outside the box.
    fn corners(&self, p: DVec3) -> Option<[(usize, f64); 8]> {
        let b = p * self.scale + self.offset;
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut w = [0f64; 3];
        for k in 0..3 {
            let n = self.n[k];
            if !(b[k] >= 0.0 && b[k] <= n as f64) {
                return None;
            }
            let x = b[k] - 0.5;
            let f = x.floor();
            w[k] = x - f;
            i0[k] = (f as i64).clamp(0, n as i64 - 1) as usize;
            i1[k] = (f as i64 + 1).clamp(0, n as i64 - 1) as usize;
        }
        Some(std::array::from_fn(|corner| {
            let pick = |k: usize| {
                if corner >> k & 1 == 0 {
                    (i0[k], 1.0 - w[k])
                } else {
                    (i1[k], w[k])
                }
            };
            let ((x, wx), (y, wy), (z, wz)) = (pick(0), pick(1), pick(2));
            ((z * self.n[1] + y) * self.n[0] + x, wx * wy * wz)
        }))
    }

    /// Adds a photon's track a→b (arc length len, ln T from la to lb, linear between)
    /// times `flux` (per channel, over the bin volume) to the bins, each bin by the
    /// integral of its trilinear weight along the track. The track is cut where it
    /// crosses a plane of bin centres or a face of the box, so each piece lies in one
    /// cell of the trilinear kernel, where the weight is a cubic in t: Simpson's rule
    /// integrates it exactly (the attenuation, smooth, to high order). Sampled at pieces'
    /// midpoints instead, oblique light through clear air read 1-4 % unevenly, in the
    /// bins' pattern.
    #[allow(clippy::too_many_arguments)]
    fn deposit(
        &self,
        acc: &mut [[f32; 3]],
        a: DVec3,
        b: DVec3,
        len: f64,
        la: [f64; 3],
        lb: [f64; 3],
        flux: [f64; 3],
    ) {
        // Cell coordinates: bin centres at the integers, the box from -0.5 to n - 0.5.
        let ca = a * self.scale + self.offset - 0.5;
        let cb = b * self.scale + self.offset - 0.5;
        let dc = cb - ca;
        let mut cuts: Vec<f64> = vec![0.0, 1.0];
        for k in 0..3 {
            if dc[k] == 0.0 {
                continue;
            }
            let (lo, hi) = (ca[k].min(cb[k]), ca[k].max(cb[k]));
            let mut m = lo.floor() + 1.0;
            while m < hi {
                cuts.push((m - ca[k]) / dc[k]);
                m += 1.0;
            }
            for face in [-0.5, self.n[k] as f64 - 0.5] {
                if face > lo && face < hi {
                    cuts.push((face - ca[k]) / dc[k]);
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        for w in cuts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if t1 <= t0 {
                continue;
            }
            let tm = 0.5 * (t0 + t1);
            let mid = ca + dc * tm;
            let mut i0 = [0usize; 3];
            let mut i1 = [0usize; 3];
            let mut cell = [0f64; 3];
            let mut outside = false;
            for k in 0..3 {
                let n = self.n[k] as f64;
                if !(mid[k] > -0.5 && mid[k] < n - 0.5) {
                    outside = true;
                }
                cell[k] = mid[k].floor();
                i0[k] = (cell[k] as i64).clamp(0, self.n[k] as i64 - 1) as usize;
                i1[k] = (cell[k] as i64 + 1).clamp(0, self.n[k] as i64 - 1) as usize;
            }
            if outside {
                continue;
            }
            let piece = (t1 - t0) * len;
            for (t, simpson) in [(t0, 1.0), (tm, 4.0), (t1, 1.0)] {
                let c = ca + dc * t;
                let f = [c.x - cell[0], c.y - cell[1], c.z - cell[2]];
                let scale: [f64; 3] =
                    std::array::from_fn(|ch| flux[ch] * transmitted(la[ch], lb[ch], t));
                let weight = simpson / 6.0 * piece;
                for corner in 0..8 {
                    let mut wgt = weight;
                    let mut idx = [0usize; 3];
                    for k in 0..3 {
                        if corner >> k & 1 == 0 {
                            wgt *= 1.0 - f[k];
                            idx[k] = i0[k];
                        } else {
                            wgt *= f[k];
                            idx[k] = i1[k];
                        }
                    }
                    let slot = &mut acc[(idx[2] * self.n[1] + idx[1]) * self.n[0] + idx[0]];
                    for ch in 0..3 {
                        slot[ch] += (wgt * scale[ch]) as f32;
                    }
                }
            }
        }
    }

    /// Trilinear between the bins' centres, clamped at the box (0 outside it).
    fn at(&self, p: DVec3) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (i, w) in self.corners(p).into_iter().flatten() {
            let f = self.fluence[i];
            for c in 0..3 {
                out[c] += w * f[c] as f64;
            }
        }
        out
    }
}

/// e^(ln T) at t in [0, 1] between ln T = la at 0 and lb at 1 (linear), where either
/// may be -inf (all absorbed).
fn transmitted(la: f64, lb: f64, t: f64) -> f64 {
    if t <= 0.0 {
        la.exp()
    } else if t >= 1.0 {
        lb.exp()
    } else if la.is_finite() && lb.is_finite() {
        (la + (lb - la) * t).exp()
    } else {
        0.0
    }
}

/// Unpolarised Fresnel reflectance of a face between η `lo` and `hi` for light whose
/// direction on the low side makes an angle with sine `sin_lo` with the normal (the same
/// both ways through the face); 1 beyond the critical angle.
pub fn fresnel(sin_lo: f64, lo: f64, hi: f64) -> f64 {
    if sin_lo >= 1.0 {
        return 1.0;
    }
    let cos_lo = (1.0 - sin_lo * sin_lo).sqrt();
    let sin_hi = sin_lo * lo / hi;
    let cos_hi = (1.0 - sin_hi * sin_hi).max(0.0).sqrt();
    let rs = (lo * cos_lo - hi * cos_hi) / (lo * cos_lo + hi * cos_hi);
    let rp = (lo * cos_hi - hi * cos_lo) / (lo * cos_hi + hi * cos_lo);
    0.5 * (rs * rs + rp * rp)
}

/// What lies beyond the volume in a world direction: the environment map (bilinear, the
/// GPU's conventions: glsl/environment.glsl, rotated about the up axis by `rotation`
/// radians) or the background.
fn behind(env: Option<&EnvironmentMap>, rotation: f64, background: [f32; 4], d: DVec3) -> [f64; 4] {
    let Some(env) = env else {
        return background.map(|c| c as f64);
    };
    let d = d.normalize();
    let (c, s) = (rotation.cos(), rotation.sin());
    let w = DVec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let phi = w.x.atan2(-w.z);
    let theta = w.y.clamp(-1.0, 1.0).asin();
    let pi = std::f64::consts::PI;
    let (wd, ht) = (env.width as i64, env.height as i64);
    let t = DVec2::new(
        (phi + pi) / (2.0 * pi) * wd as f64 - 0.5,
        (0.5 * pi - theta) / pi * ht as f64 - 0.5,
    );
    let (i, j) = (t.x.floor() as i64, t.y.floor() as i64);
    let (fx, fy) = (t.x - i as f64, t.y - j as f64);
    let texel = |x: i64, y: i64| {
        let x = x.rem_euclid(wd);
        let y = y.clamp(0, ht - 1);
        env.pixels[(y * wd + x) as usize]
    };
    let mut out = [0.0, 0.0, 0.0, 1.0];
    for (x, y, wgt) in [
        (i, j, (1.0 - fx) * (1.0 - fy)),
        (i + 1, j, fx * (1.0 - fy)),
        (i, j + 1, (1.0 - fx) * fy),
        (i + 1, j + 1, fx * fy),
    ] {
        let p = texel(x, y);
        for c in 0..3 {
            out[c] += wgt * p[c] as f64;
        }
    }
    out
}

/// Everything a viewing ray needs, shared by the workers.
struct View<'a> {
    field: &'a Field,
    light: &'a LightBins,
    env: Option<&'a EnvironmentMap>,
    rotation: f64,
    background: [f32; 4],
    ambient: [f64; 3],
    unlit: bool,
    reflections: bool,
    h: f64,
    rays: AtomicU64,
    reflected: AtomicU64,
}

impl View<'_> {
    /// The light the matter at p receives: the lights' fluence (1 unlit) and the ambient level.
    fn light_at(&self, p: DVec3) -> [f64; 3] {
        if self.unlit {
            return [1.0; 3];
        }
        let l = self.light.at(p);
        std::array::from_fn(|c| l[c] + self.ambient[c])
    }

    /// Composites the piece of path a→b (arc length len) into C, A, M.
    fn composite(
        &self,
        a: DVec3,
        b: DVec3,
        len: f64,
        c_acc: &mut [f64; 3],
        a_acc: &mut f64,
        m_acc: &mut [f64; 3],
    ) {
        let f = self.field;
        let mid = 0.5 * (a + b);
        if !f.in_box(mid) || len <= 0.0 {
            return;
        }
        let s = f.value_tex(f.tex(mid));
        let alpha = if f.clipped(mid) {
            0.0
        } else {
            lut(&f.alpha, s).clamp(0.0, 1.0)
        };
        let medium = lut3(&f.medium, s);
        // a = 1 - (1 - alpha)^(len / ref): the opacity of the piece.
        let a_piece = 1.0 - (1.0 - alpha).powf(len / f.ref_step);
        // The medium's transmittance over the piece, e^(-mu len).
        let m_piece = medium.map(|m| m.clamp(0.0, 1.0).powf(len / f.ref_step));
        if a_piece > 0.0 {
            let colour = lut3(&f.colour, s);
            let light = self.light_at(mid);
            for c in 0..3 {
                // What the piece returns, integrated exactly for constant matter: light
                // scattered at t within the piece is dimmed by the opacity and the medium
                // between, sigma * integral of e^(-(sigma + mu) t) = a_piece where mu = 0.
                // (Taking the medium only after the piece, as the sweep's compositing does,
                // is first order in the step: 0.7 % at half a voxel in the slab test.)
                let (sigma_l, mu_l) = (-(1.0 - a_piece).ln(), -m_piece[c].ln());
                let emitted = if a_piece >= 1.0 || mu_l <= 0.0 || !mu_l.is_finite() {
                    a_piece
                } else {
                    sigma_l / (sigma_l + mu_l) * (1.0 - (1.0 - a_piece) * m_piece[c])
                };
                c_acc[c] += (1.0 - *a_acc) * m_acc[c] * colour[c] * emitted * light[c];
            }
            *a_acc += (1.0 - *a_acc) * a_piece;
        }
        for c in 0..3 {
            m_acc[c] *= m_piece[c];
        }
    }

    /// The face a piece of path a→b (v = va at a) crosses, if any: (the fraction it
    /// reflects, the mirrored direction).
    fn face(&self, a: DVec3, b: DVec3, va: DVec3) -> Option<(f64, DVec3)> {
        let f = self.field;
        let (eta_a, eta_b) = (f.eta_w(a), f.eta_w(b));
        if (eta_b - eta_a).abs() < 1e-9 {
            return None;
        }
        let mid = 0.5 * (a + b);
        let g = f.grad_eta(mid);
        if g.length_squared() < 1e-24 {
            return None;
        }
        let mut n = g.normalize();
        let reach = 0.5 * (b - a).length() + PLATEAU_PROBE * f.ref_step;
        let (e_minus, e_plus) = (f.eta_w(mid - reach * n), f.eta_w(mid + reach * n));
        let (lo, hi) = (e_minus.min(e_plus), e_minus.max(e_plus));
        let middle = 0.5 * (lo + hi);
        if hi - lo < MIN_FACE_STEP || (eta_a < middle) == (eta_b < middle) {
            return None;
        }
        // A step, not a film: half-way out η lies on either side of the middle already.
        // (A film between two regions of equal η, as an opaque block's skin passing
        // through a glass's values, read as a face where one probe reached the glass
        // beyond it: measured on the GPU's eikonal view, glsl/eikonal_view.comp.)
        let (h_minus, h_plus) = (
            f.eta_w(mid - 0.5 * reach * n),
            f.eta_w(mid + 0.5 * reach * n),
        );
        if (h_minus < middle) == (h_plus < middle) {
            return None;
        }
        if e_plus < e_minus {
            n = -n; // towards higher η
        }
        // The angle on the low side from the tangential part of v (kept across a face).
        let vt = va - va.dot(n) * n;
        let sin_lo = vt.length() / lo;
        if sin_lo >= 1.0 {
            return None; // totally reflected: the ray equation turns the ray itself
        }
        let fr = fresnel(sin_lo, lo, hi);
        let eta_in = if eta_b > eta_a { lo } else { hi };
        let vn = (eta_in * eta_in - vt.length_squared()).max(0.0).sqrt();
        let incident = (vt + vn * va.dot(n).signum() * n) / eta_in;
        let mirrored = incident - 2.0 * incident.dot(n) * n;
        Some((fr, mirrored))
    }

    /// The colour and opacity seen from `origin` along the unit world direction `dir`.
    fn trace(&self, origin: DVec3, dir: DVec3, bounces: u32) -> [f64; 4] {
        self.rays.fetch_add(1, Ordering::Relaxed);
        let f = self.field;
        let (t0, t1) = ray_box(origin, dir, -f.half, f.half);
        let mut c_acc = [0.0; 3];
        let mut a_acc = 0.0;
        let mut m_acc = [1.0; 3];
        let mut out_dir = dir;
        if t1 > t0.max(0.0) {
            let mut p = origin + dir * t0.max(0.0);
            let mut v = dir * f.eta_w(p);
            let max_iter = f.max_iterations(self.h);
            for _ in 0..max_iter {
                if a_acc > 1.0 - 1e-5 {
                    break;
                }
                let speed = v.length();
                if speed.is_nan() || speed <= 0.0 || !p.is_finite() {
                    break;
                }
                let d = v / speed;
                // Left the box moving away from it: nothing more to meet.
                let beyond = p.abs().cmpgt(f.half);
                let away = (p * d).cmpgt(DVec3::ZERO);
                if (beyond & away).any() {
                    break;
                }
                let (q, vq, len) = match f.brick_at(p) {
                    Some((i, lo, hi)) if f.flags[i] & ETA_CONST != 0 => {
                        let exit = f.brick_exit(p, d, lo, hi) + f.eps;
                        let t = if f.flags[i] & TRANSPARENT != 0 {
                            exit
                        } else {
                            exit.min(self.h).min(f.next_cut(p, d) + f.eps)
                        };
                        (p + d * t, v, t)
                    }
                    Some(_) => {
                        let hh = f.next_cut(p, d).clamp(self.h * 1e-3, self.h);
                        let (q, vq) = f.rk4(p, v, hh);
                        (q, vq, hh)
                    }
                    None => break,
                };
                self.composite(p, q, len, &mut c_acc, &mut a_acc, &mut m_acc);
                if self.reflections && bounces > 0 {
                    if let Some((fr, mirrored)) = self.face(p, q, v) {
                        self.reflected.fetch_add(1, Ordering::Relaxed);
                        let seen = self.trace(p, mirrored, bounces - 1);
                        for c in 0..3 {
                            c_acc[c] += (1.0 - a_acc) * m_acc[c] * fr * seen[c];
                        }
                        a_acc += (1.0 - a_acc) * fr;
                    }
                }
                p = q;
                v = vq;
            }
            out_dir = v.normalize();
        }
        let back = behind(self.env, self.rotation, self.background, out_dir);
        let mut out = [0.0; 4];
        for c in 0..3 {
            out[c] = c_acc[c] + (1.0 - a_acc) * m_acc[c] * back[c];
        }
        out[3] = a_acc + (1.0 - a_acc) * back[3];
        out
    }
}

/// The light volume: every directional light's photons, traced and deposited.
fn trace_light(
    field: &Field,
    opts: &RenderOptions,
    ropts: &ReferenceOptions,
    threads: usize,
    progress: Progress,
) -> Result<(LightBins, u64)> {
    let mut bins = LightBins::new(field, ropts.light_bins as usize);
    let cells = bins.len();
    let bytes = cells as f64 * 12.0 * (threads + 1) as f64;
    ensure!(
        bytes <= 8e9,
        "the light volume of {}x{}x{} bins takes {:.1} GB with {threads} workers; use fewer \
         --light-bins or --threads",
        bins.n[0],
        bins.n[1],
        bins.n[2],
        bytes / 1e9
    );
    if opts.sweep.unlit {
        bins.fluence = vec![[0.0; 3]; cells];
        return Ok((bins, 0));
    }
    let half = field.half;
    let k = ropts.photons_per_voxel as f64;
    let spacing = field.ref_step / k;
    let cell = spacing * spacing;
    let h = ropts.step as f64 * field.ref_step;
    let radius = half.length() + 2.0 * field.ref_step;
    let bin_volume = bins.bin_volume();
    let mut total = vec![[0.0f32; 3]; cells];
    let mut photons = 0u64;
    for (li, light) in opts.lights.iter().enumerate() {
        ensure!(
            !light.is_point(),
            "the reference renderer follows directional lights; light {} is {}",
            li + 1,
            light.describe()
        );
        let d = light.travel().as_dvec3().normalize();
        let e1 = d.any_orthonormal_vector();
        let e2 = d.cross(e1);
        // The launch grid covers the box's shadow on the plane normal to the light.
        let r1 = half.x * e1.x.abs() + half.y * e1.y.abs() + half.z * e1.z.abs() + spacing;
        let r2 = half.x * e2.x.abs() + half.y * e2.y.abs() + half.z * e2.z.abs() + spacing;
        let (cols, rows) = (
            (2.0 * r1 / spacing).ceil() as u64,
            (2.0 * r2 / spacing).ceil() as u64,
        );
        let start = -radius * d;
        let target = Target { n: d, c: radius };
        let steps = (cols * rows) as f64 * (2.0 * radius / h);
        if let Some(max) = ropts.max_steps {
            ensure!(
                steps <= max,
                "light {}: {} photons of up to {:.0} steps each exceed the limit of {max:.1e} \
                 RK4 steps; use fewer --photons-per-voxel, a larger --step, or raise \
                 --max-steps",
                li + 1,
                cols * rows,
                2.0 * radius / h
            );
        }
        let colour = light.colour.map(|c| c as f64);
        let next_row = AtomicUsize::new(0);
        let label = format!("light {}", li + 1);
        let work = || {
            let mut acc = vec![[0.0f32; 3]; cells];
            loop {
                let r = next_row.fetch_add(1, Ordering::Relaxed) as u64;
                if r >= rows {
                    break;
                }
                progress(&label, r, rows);
                for c in 0..cols {
                    let x = -r1 + (c as f64 + 0.5) * spacing;
                    let y = -r2 + (r as f64 + 0.5) * spacing;
                    let p = start + e1 * x + e2 * y;
                    let v = d * field.eta_w(p);
                    let mut deposit = |a: DVec3, b: DVec3, len: f64, la: [f64; 3], lb: [f64; 3]| {
                        if len > 0.0 && la.iter().any(|l| *l >= FLUX_CUTOFF.ln()) {
                            let flux = colour.map(|c| c * cell / bin_volume);
                            bins.deposit(&mut acc, a, b, len, la, lb, flux);
                        }
                    };
                    field.trace(p, v, target, h, true, &mut deposit);
                }
            }
            acc
        };
        let parts = crate::workers::run(threads, "photon", work)?;
        for part in parts {
            for (t, a) in total.iter_mut().zip(part) {
                for c in 0..3 {
                    t[c] += a[c];
                }
            }
        }
        photons += cols * rows;
    }
    bins.fluence = total;
    Ok((bins, photons))
}

/// `progress(phase, done, of)`: rows of photons or pixels done, from the worker threads.
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// A reference image of the scene through `camera` at the size of `opts` (see the
/// module documentation); `progress(phase, done, of)`, if given, is called as rows of
/// photons and pixels finish (from the worker threads).
pub fn render_reference(
    volume: &Volume,
    tf: &TransferFunctions,
    env: Option<&EnvironmentMap>,
    camera: &Camera,
    opts: &RenderOptions,
    ropts: &ReferenceOptions,
    progress: Option<Progress>,
) -> Result<ReferenceImage> {
    let progress = progress.unwrap_or(&|_, _, _| {});
    ropts.validate()?;
    camera.validate()?;
    opts.validate()?;
    let mut field = Field::new(volume, tf, opts)?;
    if ropts.cubic_eta {
        field.use_cubic_eta();
    }
    let threads = crate::workers::count(ropts.threads)?;
    let (w, h) = (opts.width as usize, opts.height as usize);
    let k = ropts.rays_per_pixel as usize;
    let step = ropts.step as f64 * field.ref_step;
    if let Some(max) = ropts.max_steps {
        let per_ray = 2.0 * field.half.length() / step;
        let steps = (w * h * k * k) as f64 * per_ray;
        ensure!(
            steps <= max,
            "{} viewing rays of up to {per_ray:.0} steps each exceed the limit of {max:.1e} \
             RK4 steps; use a smaller image, fewer --rays-per-pixel, a larger --step, or \
             raise --max-steps",
            w * h * k * k
        );
    }

    let start = Instant::now();
    let (light, photons) = trace_light(&field, opts, ropts, threads, progress)?;
    let light_seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let view = View {
        field: &field,
        light: &light,
        env,
        rotation: (opts.sweep.env_rotation as f64).to_radians(),
        background: opts.background,
        ambient: opts.sweep.ambient.map(|c| c as f64),
        unlit: opts.sweep.unlit,
        reflections: opts.sweep.reflections,
        h: step,
        rays: AtomicU64::new(0),
        reflected: AtomicU64::new(0),
    };
    let (eye, forward, right, up) = camera.frame();
    let (eye, forward, right, up) = (
        eye.as_dvec3(),
        forward.as_dvec3(),
        right.as_dvec3(),
        up.as_dvec3(),
    );
    let tanf = ((camera.fov_y as f64).to_radians() * 0.5).tan();
    let aspect = w as f64 / h as f64;
    let next_row = AtomicUsize::new(0);
    let work = || {
        let mut rows = Vec::new();
        loop {
            let j = next_row.fetch_add(1, Ordering::Relaxed);
            if j >= h {
                break;
            }
            progress("view", j as u64, h as u64);
            let mut row = vec![[0.0f32; 4]; w];
            for (i, px) in row.iter_mut().enumerate() {
                let mut sum = [0.0f64; 4];
                for sj in 0..k {
                    for si in 0..k {
                        // The GPU's camera_ray at the sub-pixel's centre.
                        let nx = (i as f64 + (si as f64 + 0.5) / k as f64) / w as f64 * 2.0 - 1.0;
                        let ny = (j as f64 + (sj as f64 + 0.5) / k as f64) / h as f64 * 2.0 - 1.0;
                        let dir =
                            (forward + nx * tanf * aspect * right - ny * tanf * up).normalize();
                        let seen = view.trace(eye, dir, ropts.bounces);
                        for c in 0..4 {
                            sum[c] += seen[c];
                        }
                    }
                }
                *px = sum.map(|s| (s / (k * k) as f64) as f32);
            }
            rows.push((j, row));
        }
        rows
    };
    let parts = crate::workers::run(threads, "viewing ray", work)?;
    let mut pixels = vec![[0.0f32; 4]; w * h];
    for (j, row) in parts.into_iter().flatten() {
        pixels[j * w..(j + 1) * w].copy_from_slice(&row);
    }
    Ok(ReferenceImage {
        width: opts.width,
        height: opts.height,
        pixels,
        photons,
        bins: light.n,
        rays: view.rays.load(Ordering::Relaxed),
        reflected: view.reflected.load(Ordering::Relaxed),
        light_seconds,
        view_seconds: start.elapsed().as_secs_f64(),
        threads,
    })
}

#[cfg(test)]
#[path = "reference_tests.rs"]
mod tests;

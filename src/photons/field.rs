//! The photon tracer's field: the volume's values, η and extinction as the GPU samples
//! them, the bricks that let rays skip empty space, and the RK4 ray integration.

use super::*;

/// Normalised [0,1] values as the GPU texture returns them.
pub(super) fn normalised_values(volume: &Volume) -> Vec<f32> {
    match &volume.voxels {
        Voxels::U8(v) => v.iter().map(|&x| x as f32 / 255.0).collect(),
        Voxels::U16(v) => v.iter().map(|&x| x as f32 / 65535.0).collect(),
        Voxels::F32(_) => bytemuck::pod_collect_to_vec(&volume.texel_bytes()),
    }
}

pub(super) fn lut(tab: &[f32], s: f64) -> f64 {
    let x = s.clamp(0.0, 1.0) * (tab.len() - 1) as f64;
    let i = (x as usize).min(tab.len() - 2);
    let f = x - i as f64;
    tab[i] as f64 * (1.0 - f) + tab[i + 1] as f64 * f
}

/// d lut(tab, s) / ds: the slope of the table's segment holding s (0 outside [0, 1]).
pub(super) fn lut_slope(tab: &[f32], s: f64) -> f64 {
    if !(0.0..=1.0).contains(&s) {
        return 0.0;
    }
    let n = (tab.len() - 1) as f64;
    let i = ((s * n) as usize).min(tab.len() - 2);
    (tab[i + 1] - tab[i]) as f64 * n
}

pub(super) fn lut3(tab: &[[f32; 3]], s: f64) -> [f64; 3] {
    let x = s.clamp(0.0, 1.0) * (tab.len() - 1) as f64;
    let i = (x as usize).min(tab.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|c| tab[i][c] as f64 * (1.0 - f) + tab[i + 1][c] as f64 * f)
}

/// Table entries a lookup of any s in [lo, hi] can touch with a non-zero weight.
pub(super) fn lut_range(lo: f64, hi: f64) -> std::ops::RangeInclusive<usize> {
    let n = TF_SAMPLES as usize;
    let a = (lo.clamp(0.0, 1.0) * (n - 1) as f64).floor() as usize;
    let b = (hi.clamp(0.0, 1.0) * (n - 1) as f64).ceil() as usize;
    a.min(n - 1)..=b.min(n - 1)
}

/// Slab test: (t_enter, t_exit) of the line p + t d with the box [lo, hi].
pub(super) fn ray_box(p: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> (f64, f64) {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for k in 0..3 {
        if d[k] != 0.0 {
            let a = (lo[k] - p[k]) / d[k];
            let b = (hi[k] - p[k]) / d[k];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        } else if p[k] < lo[k] || p[k] > hi[k] {
            return (f64::INFINITY, f64::NEG_INFINITY);
        }
    }
    (t0, t1)
}

pub(super) fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

pub(super) fn uniform(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

impl Field {
    /// The field of `volume` with `tf`, the eta scale and the clipping plane of `opts`.
    pub fn new(volume: &Volume, tf: &TransferFunctions, opts: &RenderOptions) -> Result<Self> {
        volume.validate()?;
        opts.sweep.validate()?;
        let dims = volume.dims.map(|d| d as usize);
        let values = normalised_values(volume);
        let half = Vec3::from(volume.normalised_extent()).as_dvec3() * 0.5;
        let ref_step = volume.min_voxel_size() as f64;
        let k = opts.sweep.eta_scale;
        let (l0, l1) = tf.texels();
        let eta: Vec<f32> = l1
            .iter()
            .map(|t| {
                if k == 1.0 {
                    t[3]
                } else {
                    1.0 + k * (t[3] - 1.0)
                }
            })
            .collect();
        let alpha: Vec<f32> = l0.iter().map(|t| t[3]).collect();
        let medium: Vec<[f32; 3]> = l1.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let colour: Vec<[f32; 3]> = l0.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let clip = opts
            .sweep
            .clip
            .map(|(n, o)| (n.normalize().as_dvec3(), o as f64));
        let tex_per_world = DVec3::splat(0.5) / half;
        let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let vox_scale = tex_per_world * n;
        let vox_offset = 0.5 * n - 0.5;
        let b = BRICK as f64;
        let g0 = -0.5 - b;
        let nb = dims.map(|d| (d + 2 * BRICK).div_ceil(BRICK));
        let grid_lo = (DVec3::splat(g0) - vox_offset) / vox_scale;
        let grid_hi = (DVec3::new(
            g0 + nb[0] as f64 * b,
            g0 + nb[1] as f64 * b,
            g0 + nb[2] as f64 * b,
        ) - vox_offset)
            / vox_scale;
        let mut f = Self {
            dims,
            values,
            tex_per_world,
            half,
            ref_step,
            eta,
            alpha,
            medium,
            colour,
            clip,
            rate0: [0.0; 3],
            rate0_clipped: [0.0; 3],
            exterior_transparent: false,
            cubic_eta: false,
            g0,
            nb,
            flags: Vec::new(),
            vox_scale,
            vox_offset,
            grid_lo,
            grid_hi,
            eps: 1e-6 * ref_step,
        };
        f.rate0 = f.rate_of(0.0, false);
        f.rate0_clipped = f.rate_of(0.0, true);
        f.exterior_transparent = f.rate0 == [0.0; 3] && f.rate0_clipped == [0.0; 3];
        f.flags = f.brick_flags();
        Ok(f)
    }

    pub(super) fn brick_flags(&self) -> Vec<u8> {
        let [nx, ny, nz] = self.nb;
        let b = BRICK as f64;
        // How far beyond a brick the values that η inside it reads lie: the gradient's
        // stencil, and the cubic B-spline's support (one more voxel either side).
        let h = GRADIENT_STEP + if self.cubic_eta { 1.0 } else { 0.0 };
        let mut flags = vec![0u8; nx * ny * nz];
        for jz in 0..nz {
            for jy in 0..ny {
                for jx in 0..nx {
                    let j = [jx, jy, jz];
                    let mut outside = false;
                    let mut inside = true;
                    let mut range = [(0usize, 0usize); 3];
                    for k in 0..3 {
                        let n = self.dims[k] as f64;
                        let lo = self.g0 + j[k] as f64 * b - h;
                        let hi = self.g0 + (j[k] + 1) as f64 * b + h;
                        if lo < -0.5 || hi > n - 0.5 {
                            outside = true;
                        }
                        if lo > n - 0.5 || hi < -0.5 {
                            inside = false;
                        }
                        let a = lo.max(-0.5).floor().clamp(0.0, n - 1.0) as usize;
                        let c = (hi.min(n - 0.5).floor() + 1.0).clamp(0.0, n - 1.0) as usize;
                        range[k] = (a, c);
                    }
                    let (mut smin, mut smax) = if outside {
                        (0.0f64, 0.0f64)
                    } else {
                        (f64::INFINITY, f64::NEG_INFINITY)
                    };
                    if inside {
                        for z in range[2].0..=range[2].1 {
                            for y in range[1].0..=range[1].1 {
                                let row = (z * self.dims[1] + y) * self.dims[0];
                                for x in range[0].0..=range[0].1 {
                                    let v = self.values[row + x] as f64;
                                    smin = smin.min(v);
                                    smax = smax.max(v);
                                }
                            }
                        }
                    }
                    let r = lut_range(smin, smax);
                    let e0 = self.eta[*r.start()];
                    let mut fl = 0;
                    if self.eta[r.clone()].iter().all(|&e| e == e0) {
                        fl |= ETA_CONST;
                    }
                    if self.alpha[r.clone()].iter().all(|&a| a == 0.0)
                        && self.medium[r].iter().all(|m| *m == [1.0; 3])
                    {
                        fl |= TRANSPARENT;
                    }
                    flags[(jz * ny + jy) * nx + jx] = fl;
                }
            }
        }
        flags
    }

    /// The smallest voxel side in world units.
    pub fn ref_step(&self) -> f32 {
        self.ref_step as f32
    }

    /// Half extent of the volume box in world units.
    pub fn half_extent(&self) -> Vec3 {
        self.half.as_vec3()
    }

    pub(super) fn texel(&self, x: usize, y: usize, z: usize) -> f64 {
        self.values[(z * self.dims[1] + y) * self.dims[0] + x] as f64
    }

    /// Scalar value at texture coordinate t: trilinear, clamp to edge, 0 outside [0,1]³.
    pub(super) fn value_tex(&self, t: DVec3) -> f64 {
        if t.x < 0.0 || t.y < 0.0 || t.z < 0.0 || t.x > 1.0 || t.y > 1.0 || t.z > 1.0 {
            return 0.0;
        }
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut w = [0f64; 3];
        for k in 0..3 {
            let n = self.dims[k];
            let x = t[k] * n as f64 - 0.5;
            let f = x.floor();
            w[k] = x - f;
            let i = f as i64;
            i0[k] = i.clamp(0, n as i64 - 1) as usize;
            i1[k] = (i + 1).clamp(0, n as i64 - 1) as usize;
        }
        let c = |x: usize, y: usize, z: usize| self.texel(x, y, z);
        let x00 = c(i0[0], i0[1], i0[2]) * (1.0 - w[0]) + c(i1[0], i0[1], i0[2]) * w[0];
        let x10 = c(i0[0], i1[1], i0[2]) * (1.0 - w[0]) + c(i1[0], i1[1], i0[2]) * w[0];
        let x01 = c(i0[0], i0[1], i1[2]) * (1.0 - w[0]) + c(i1[0], i0[1], i1[2]) * w[0];
        let x11 = c(i0[0], i1[1], i1[2]) * (1.0 - w[0]) + c(i1[0], i1[1], i1[2]) * w[0];
        let y0 = x00 * (1.0 - w[1]) + x10 * w[1];
        let y1 = x01 * (1.0 - w[1]) + x11 * w[1];
        y0 * (1.0 - w[2]) + y1 * w[2]
    }

    pub(super) fn tex(&self, p: DVec3) -> DVec3 {
        p * self.tex_per_world + 0.5
    }

    /// Scalar value s at a world position (0 outside the box).
    pub fn value(&self, p: Vec3) -> f32 {
        self.value_tex(self.tex(p.as_dvec3())) as f32
    }

    /// η at a world position.
    pub fn eta_at(&self, p: Vec3) -> f32 {
        lut(&self.eta, self.value_tex(self.tex(p.as_dvec3()))) as f32
    }

    pub(super) fn eta_w(&self, p: DVec3) -> f64 {
        let t = self.tex(p);
        let s = if self.cubic_eta {
            self.value_grad_cubic(t).0
        } else {
            self.value_tex(t)
        };
        lut(&self.eta, s)
    }

    /// ∇η (world units): by central differences GRADIENT_STEP voxels apart of the
    /// trilinear field, or the cubic B-spline field's own ([`Self::use_cubic_eta`]).
    pub(super) fn grad_eta(&self, p: DVec3) -> DVec3 {
        let t = self.tex(p);
        if self.cubic_eta {
            let (s, g) = self.value_grad_cubic(t);
            return lut_slope(&self.eta, s) * g;
        }
        self.grad_eta_trilinear(t)
    }

    /// η and the refraction it causes from the value interpolated with the cubic
    /// B-spline (C², so its iso-surfaces are smooth) instead of trilinearly; the matter
    /// (opacity, colour, medium) stays trilinear, as the GPU samples it. The trilinear
    /// field's iso-surfaces are corrugated with a period of one voxel: a ray through a
    /// planar face swings by ±1.5° (docs/NOTES.md), and the view through a glass ball
    /// departs from Snell's law by 1° RMS, up to 3° (the reference renderer's test),
    /// scattering the checkered environment seen through it into speckle. The B-spline
    /// reproduces linear ramps exactly, so a planar face stays where it is; it smooths
    /// curvature below a voxel or two. The bricks' test widens by the spline's support.
    pub fn use_cubic_eta(&mut self) {
        self.cubic_eta = true;
        self.flags = self.brick_flags();
    }

    /// The cubic B-spline interpolation of the value at texture coordinate t (clamped
    /// at the volume's edge, 0 outside [0,1]³, as the trilinear one) and its gradient in
    /// world units.
    pub(super) fn value_grad_cubic(&self, t: DVec3) -> (f64, DVec3) {
        if t.x < 0.0 || t.y < 0.0 || t.z < 0.0 || t.x > 1.0 || t.y > 1.0 || t.z > 1.0 {
            return (0.0, DVec3::ZERO);
        }
        let mut idx = [[0usize; 4]; 3];
        let mut w = [[0f64; 4]; 3];
        let mut dw = [[0f64; 4]; 3];
        for k in 0..3 {
            let n = self.dims[k] as i64;
            let x = t[k] * n as f64 - 0.5;
            let i = x.floor();
            let f = x - i;
            let g = 1.0 - f;
            w[k] = [
                g * g * g / 6.0,
                (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0,
                (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0,
                f * f * f / 6.0,
            ];
            dw[k] = [
                -0.5 * g * g,
                1.5 * f * f - 2.0 * f,
                -1.5 * f * f + f + 0.5,
                0.5 * f * f,
            ];
            for (m, slot) in idx[k].iter_mut().enumerate() {
                *slot = (i as i64 - 1 + m as i64).clamp(0, n - 1) as usize;
            }
        }
        let (mut s, mut g) = (0.0, DVec3::ZERO);
        for c in 0..4 {
            for b in 0..4 {
                let row = (idx[2][c] * self.dims[1] + idx[1][b]) * self.dims[0];
                let (mut v, mut vx) = (0.0, 0.0);
                for a in 0..4 {
                    let x = self.values[row + idx[0][a]] as f64;
                    v += w[0][a] * x;
                    vx += dw[0][a] * x;
                }
                s += w[2][c] * w[1][b] * v;
                g += DVec3::new(
                    w[2][c] * w[1][b] * vx,
                    w[2][c] * dw[1][b] * v,
                    dw[2][c] * w[1][b] * v,
                );
            }
        }
        (s, g * self.vox_scale)
    }

    /// ∇η by central differences of the trilinear field, GRADIENT_STEP voxels apart.
    fn grad_eta_trilinear(&self, t: DVec3) -> DVec3 {
        if let Some(g) = self.grad_eta_in_cell(t) {
            return g;
        }
        let mut g = DVec3::ZERO;
        for k in 0..3 {
            let h = GRADIENT_STEP / self.dims[k] as f64;
            let mut e = DVec3::ZERO;
            e[k] = h;
            let a = lut(&self.eta, self.value_tex(t + e));
            let b = lut(&self.eta, self.value_tex(t - e));
            g[k] = (a - b) / (2.0 * h) * self.tex_per_world[k];
        }
        g
    }

    /// [`Self::grad_eta`] when all six stencil points lie in the box and in one trilinear
    /// cell (the common case): the same values from one fetch of the cell's corners.
    pub(super) fn grad_eta_in_cell(&self, t: DVec3) -> Option<DVec3> {
        let hv = GRADIENT_STEP;
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut w = [0f64; 3];
        for k in 0..3 {
            let n = self.dims[k];
            let h = hv / n as f64;
            if t[k] - h < 0.0 || t[k] + h > 1.0 {
                return None;
            }
            let x = t[k] * n as f64 - 0.5;
            let f = x.floor();
            w[k] = x - f;
            if w[k] < hv || w[k] > 1.0 - hv {
                return None;
            }
            let i = f as i64;
            i0[k] = i.clamp(0, n as i64 - 1) as usize;
            i1[k] = (i + 1).clamp(0, n as i64 - 1) as usize;
        }
        let c = |x: usize, y: usize, z: usize| self.texel(x, y, z);
        let v = [
            c(i0[0], i0[1], i0[2]),
            c(i1[0], i0[1], i0[2]),
            c(i0[0], i1[1], i0[2]),
            c(i1[0], i1[1], i0[2]),
            c(i0[0], i0[1], i1[2]),
            c(i1[0], i0[1], i1[2]),
            c(i0[0], i1[1], i1[2]),
            c(i1[0], i1[1], i1[2]),
        ];
        let tri = |w: [f64; 3]| {
            let x00 = v[0] * (1.0 - w[0]) + v[1] * w[0];
            let x10 = v[2] * (1.0 - w[0]) + v[3] * w[0];
            let x01 = v[4] * (1.0 - w[0]) + v[5] * w[0];
            let x11 = v[6] * (1.0 - w[0]) + v[7] * w[0];
            let y0 = x00 * (1.0 - w[1]) + x10 * w[1];
            let y1 = x01 * (1.0 - w[1]) + x11 * w[1];
            y0 * (1.0 - w[2]) + y1 * w[2]
        };
        let mut g = DVec3::ZERO;
        for k in 0..3 {
            let (mut a, mut b) = (w, w);
            a[k] += hv;
            b[k] -= hv;
            let h = hv / self.dims[k] as f64;
            g[k] = (lut(&self.eta, tri(a)) - lut(&self.eta, tri(b))) / (2.0 * h)
                * self.tex_per_world[k];
        }
        Some(g)
    }

    pub(super) fn clipped(&self, p: DVec3) -> bool {
        match self.clip {
            Some((n, o)) => n.dot(p) > o,
            None => false,
        }
    }

    /// −d(ln flux)/ds per channel for the value s.
    pub(super) fn rate_of(&self, s: f64, clipped: bool) -> [f64; 3] {
        let sigma = if clipped {
            0.0
        } else {
            let a = lut(&self.alpha, s).clamp(0.0, 1.0);
            -(1.0 - a).ln() / self.ref_step
        };
        let m = lut3(&self.medium, s);
        std::array::from_fn(|c| sigma - m[c].clamp(0.0, 1.0).ln() / self.ref_step)
    }

    pub(super) fn rate(&self, p: DVec3) -> [f64; 3] {
        self.rate_of(self.value_tex(self.tex(p)), self.clipped(p))
    }

    pub(super) fn add_rate(log_t: &mut [f64; 3], r: [f64; 3], len: f64) {
        if len > 0.0 {
            for c in 0..3 {
                if r[c] > 0.0 {
                    log_t[c] -= r[c] * len;
                }
            }
        }
    }

    /// Attenuation along the chord a→b of arc length `len` (two-point Gauss–Legendre).
    pub(super) fn integrate_chord(&self, a: DVec3, b: DVec3, len: f64, log_t: &mut [f64; 3]) {
        const G: f64 = 0.288_675_134_594_812_9; // 1 / (2 sqrt 3)
        for tau in [0.5 - G, 0.5 + G] {
            Self::add_rate(log_t, self.rate(a + (b - a) * tau), 0.5 * len);
        }
    }

    pub(super) fn in_box(&self, p: DVec3) -> bool {
        p.abs().cmple(self.half).all()
    }

    /// Attenuation along the straight segment p + t d, t in [0, len], split where the
    /// integrand jumps (box faces, clipping plane); uniform outside the box.
    pub(super) fn attenuate_straight(
        &self,
        p: DVec3,
        d: DVec3,
        len: f64,
        h: f64,
        log_t: &mut [f64; 3],
    ) {
        if len <= 0.0 {
            return;
        }
        let mut cuts = [0.0, len, len, len, len];
        let mut n = 2;
        let (t0, t1) = ray_box(p, d, -self.half, self.half);
        for t in [t0, t1] {
            if t > 0.0 && t < len {
                cuts[n] = t;
                n += 1;
            }
        }
        if let Some((cn, co)) = self.clip {
            let dn = cn.dot(d);
            if dn != 0.0 {
                let t = (co - cn.dot(p)) / dn;
                if t > 0.0 && t < len {
                    cuts[n] = t;
                    n += 1;
                }
            }
        }
        let cuts = &mut cuts[..n];
        cuts.sort_by(f64::total_cmp);
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b <= a {
                continue;
            }
            let mid = p + d * (0.5 * (a + b));
            if !self.in_box(mid) {
                let r = if self.clipped(mid) {
                    self.rate0_clipped
                } else {
                    self.rate0
                };
                Self::add_rate(log_t, r, b - a);
                continue;
            }
            let steps = ((b - a) / h).ceil().max(1.0);
            let dt = (b - a) / steps;
            for i in 0..steps as usize {
                let s0 = a + i as f64 * dt;
                self.integrate_chord(p + d * s0, p + d * (s0 + dt), dt, log_t);
            }
        }
    }

    /// Brick index and voxel-space bounds of the brick holding p, None outside the grid.
    pub(super) fn brick_at(&self, p: DVec3) -> Option<(usize, DVec3, DVec3)> {
        let x = p * self.vox_scale + self.vox_offset;
        let b = BRICK as f64;
        let mut j = [0usize; 3];
        for k in 0..3 {
            let f = ((x[k] - self.g0) / b).floor();
            if !(f >= 0.0 && f < self.nb[k] as f64) {
                return None;
            }
            j[k] = f as usize;
        }
        let lo = DVec3::new(
            self.g0 + j[0] as f64 * b,
            self.g0 + j[1] as f64 * b,
            self.g0 + j[2] as f64 * b,
        );
        Some(((j[2] * self.nb[1] + j[1]) * self.nb[0] + j[0], lo, lo + b))
    }

    pub(super) fn flags_at(&self, p: DVec3) -> u8 {
        self.brick_at(p)
            .map(|(i, _, _)| self.flags[i])
            .unwrap_or(if self.exterior_transparent {
                ETA_CONST | TRANSPARENT
            } else {
                ETA_CONST
            })
    }

    /// World distance along unit d from p to the exit of the brick with voxel bounds lo, hi.
    pub(super) fn brick_exit(&self, p: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> f64 {
        let x = p * self.vox_scale + self.vox_offset;
        let dv = d * self.vox_scale;
        // An axis the ray is all but parallel to gives no exit: a ray on a brick's face
        // (x = 0 of a symmetric scene) whose direction picked up a component of 1e-17
        // towards it from rounding would otherwise exit at distance 0 on every
        // iteration, move by eps · 1e-17 (nothing) and be lost at the iteration limit.
        // Over a brick it drifts by less than 1e-8 voxel along such an axis.
        let parallel = 1e-9 * dv.abs().max_element();
        let mut t = f64::INFINITY;
        for k in 0..3 {
            if dv[k] > parallel {
                t = t.min((hi[k] - x[k]) / dv[k]);
            } else if dv[k] < -parallel {
                t = t.min((lo[k] - x[k]) / dv[k]);
            }
        }
        t.max(0.0)
    }

    /// Distance along unit d to the next place where the integrand jumps (box face,
    /// clipping plane), infinity if none.
    pub(super) fn next_cut(&self, p: DVec3, d: DVec3) -> f64 {
        let tiny = 1e-9;
        let mut best = f64::INFINITY;
        let (t0, t1) = ray_box(p, d, -self.half, self.half);
        if t0 <= t1 {
            for t in [t0, t1] {
                if t > tiny {
                    best = best.min(t);
                }
            }
        }
        if let Some((cn, co)) = self.clip {
            let dn = cn.dot(d);
            if dn != 0.0 {
                let t = (co - cn.dot(p)) / dn;
                if t > tiny {
                    best = best.min(t);
                }
            }
        }
        best
    }

    pub(super) fn rk4(&self, p: DVec3, v: DVec3, h: f64) -> (DVec3, DVec3) {
        let k1x = v.normalize();
        let k1v = self.grad_eta(p);
        let v2 = v + 0.5 * h * k1v;
        let k2x = v2.normalize();
        let k2v = self.grad_eta(p + 0.5 * h * k1x);
        let v3 = v + 0.5 * h * k2v;
        let k3x = v3.normalize();
        let k3v = self.grad_eta(p + 0.5 * h * k2x);
        let v4 = v + h * k3v;
        let k4x = v4.normalize();
        let k4v = self.grad_eta(p + h * k3x);
        (
            p + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }

    pub(super) fn max_iterations(&self, h: f64) -> u64 {
        let diag = (self.grid_hi - self.grid_lo).length();
        (50.0 * diag / h) as u64 + 100_000
    }

    /// Trace from p with v = η d until the target plane is crossed moving forward; the
    /// plane's normal is the view direction (for the steepness statistic).
    ///
    /// `visit(a, b, len, log_t at a, log_t at b)` is called for every piece of the path
    /// (a chord of arc length `len`), in order: the reference renderer's light volume
    /// deposits the photon's flux along it ([`super::reference`]).
    pub(super) fn trace(
        &self,
        mut p: DVec3,
        mut v: DVec3,
        target: Target,
        h: f64,
        cutoff: bool,
        visit: &mut impl FnMut(DVec3, DVec3, f64, [f64; 3], [f64; 3]),
    ) -> Trace {
        let ln_cut = FLUX_CUTOFF.ln();
        let mut log_t = [0.0f64; 3];
        let mut min_forward = f64::INFINITY;
        let mut length = 0.0;
        let max_iter = self.max_iterations(h);
        let eps = self.eps;
        let mut end = End::Lost;
        for _ in 0..max_iter {
            let speed = v.length();
            if speed.is_nan() || speed <= 0.0 || !p.is_finite() {
                break;
            }
            let d = v / speed;
            let dz = d.dot(target.n);
            min_forward = min_forward.min(dz);
            let zrel = target.n.dot(p) - target.c;
            let t_plane = if dz > 0.0 { -zrel / dz } else { f64::INFINITY };
            match self.brick_at(p) {
                None => {
                    let (t0, t1) = ray_box(p, d, self.grid_lo, self.grid_hi);
                    let t_grid = if t0 >= 0.0 && t0 <= t1 {
                        t0
                    } else {
                        f64::INFINITY
                    };
                    if t_plane <= t_grid {
                        if !t_plane.is_finite() {
                            end = End::Backward;
                            break;
                        }
                        let before = log_t;
                        if !self.exterior_transparent {
                            self.attenuate_straight(p, d, t_plane, h, &mut log_t);
                        }
                        visit(p, p + d * t_plane, t_plane, before, log_t);
                        p += d * t_plane;
                        length += t_plane;
                        end = End::Plane;
                        break;
                    }
                    let t = t_grid + eps;
                    let before = log_t;
                    if !self.exterior_transparent {
                        self.attenuate_straight(p, d, t, h, &mut log_t);
                    }
                    visit(p, p + d * t, t, before, log_t);
                    p += d * t;
                    length += t;
                }
                Some((i, lo, hi)) if self.flags[i] & ETA_CONST != 0 => {
                    let t_exit = self.brick_exit(p, d, lo, hi) + eps;
                    let t = t_exit.min(t_plane);
                    if self.flags[i] & TRANSPARENT == 0 {
                        // In steps of at most h, each visited with its own attenuation:
                        // the matter may change within the brick (a surface), where
                        // interpolating ln T across the whole brick spread its
                        // attenuation over the brick (the reference's light volume had
                        // a lattice of the bricks' period on a lit floor).
                        let steps = (t / h).ceil().max(1.0);
                        let dt = t / steps;
                        for k in 0..steps as usize {
                            let a = p + d * (k as f64 * dt);
                            let before = log_t;
                            self.attenuate_straight(a, d, dt, h, &mut log_t);
                            visit(a, a + d * dt, dt, before, log_t);
                        }
                    } else {
                        visit(p, p + d * t, t, log_t, log_t);
                    }
                    p += d * t;
                    length += t;
                    if t_plane <= t_exit {
                        end = End::Plane;
                        break;
                    }
                }
                Some((i, _, _)) => {
                    let hh = self.next_cut(p, d).clamp(h * 1e-3, h);
                    let (p1, v1) = self.rk4(p, v, hh);
                    let z1 = target.n.dot(p1) - target.c;
                    let frac = if z1 >= 0.0 { zrel / (zrel - z1) } else { 1.0 };
                    let q = p + (p1 - p) * frac;
                    let before = log_t;
                    if self.flags[i] & TRANSPARENT == 0 || self.flags_at(p1) & TRANSPARENT == 0 {
                        self.integrate_chord(p, q, hh * frac, &mut log_t);
                    }
                    visit(p, q, hh * frac, before, log_t);
                    length += hh * frac;
                    if z1 >= 0.0 {
                        p = q;
                        v = v + (v1 - v) * frac;
                        end = End::Plane;
                        break;
                    }
                    p = p1;
                    v = v1;
                }
            }
            if cutoff && log_t.iter().all(|&l| l < ln_cut) {
                end = End::Absorbed;
                break;
            }
        }
        if let Some(&l) = log_t.iter().find(|l| l.is_nan()) {
            let _ = l;
            log_t = [f64::NEG_INFINITY; 3];
        }
        Trace {
            end,
            p,
            v,
            log_t,
            min_forward,
            length,
        }
    }

    /// Traces one ray from the world point `origin` along the world direction `direction`
    /// (starting with v = η(origin)·direction) until it crosses the view-aligned plane at
    /// view depth `depth` of `camera` moving forward; `step` is the RK4 step in voxels.
    /// Light is not cut off by absorption (see the transmittance). None if the ray turns
    /// back and never reaches the plane (or hits the iteration limit).
    pub fn trace_ray(
        &self,
        camera: &Camera,
        origin: Vec3,
        direction: Vec3,
        depth: f32,
        step: f32,
    ) -> Result<Option<RayEnd>> {
        ensure!(
            step.is_finite() && step > 0.0,
            "ray step {step} must be a positive number of voxels"
        );
        ensure!(
            direction.is_finite() && direction.length() > 0.0,
            "ray direction {direction:?} must be a finite non-zero vector"
        );
        let (eye, forward, _, _) = camera.frame();
        let target = Target {
            n: forward.as_dvec3(),
            c: depth as f64 + forward.as_dvec3().dot(eye.as_dvec3()),
        };
        let p = origin.as_dvec3();
        ensure!(
            target.n.dot(p) < target.c,
            "ray origin {origin:?} is already at or beyond view depth {depth}"
        );
        let v = direction.as_dvec3().normalize() * self.eta_w(p);
        let t = self.trace(
            p,
            v,
            target,
            step as f64 * self.ref_step,
            false,
            &mut |_, _, _, _, _| {},
        );
        if t.end != End::Plane {
            return Ok(None);
        }
        Ok(Some(RayEnd {
            position: t.p.as_vec3(),
            direction: t.v.normalize().as_vec3(),
            eta: t.v.length() as f32,
            transmittance: t.log_t.map(|l| l.exp() as f32),
            length: t.length as f32,
        }))
    }
}

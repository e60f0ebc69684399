//! The light on one plane: photons launched on a grid, traced, and box-binned where they
//! cross the target plane, as fluence (the default) or flux per unit plane area.

use super::*;

/// Irradiance of the scene's directional light on the view-aligned plane at view depth
/// `depth` (see the module documentation), as a W × H image of `opts`; `progress(rows
/// done, rows)`, if given, is called as launch rows finish (from the worker threads).
pub fn trace_irradiance(
    volume: &Volume,
    tf: &TransferFunctions,
    camera: &Camera,
    opts: &RenderOptions,
    depth: f32,
    popts: &PhotonOptions,
    progress: Option<&(dyn Fn(u64, u64) + Sync)>,
) -> Result<PhotonImage> {
    let progress = progress.unwrap_or(&|_, _| {});
    popts.validate()?;
    // The tracer is the sweep's reference: it takes what the sweep takes, one directional
    // light.
    let support = crate::render::Model::Refract.light_support();
    ensure!(
        opts.lights.len() <= support.max && !opts.light().is_point(),
        "the photon tracer follows the sweep's one directional light; got {}",
        opts.lights
            .iter()
            .map(|l| l.describe())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let planes = planes(volume, camera, opts)?;
    let field = Field::new(volume, tf, opts)?;
    let start = Instant::now();
    let (eye, forward, right, up) = camera.frame();
    // The f32 frame, re-orthonormalised in f64: launch and binning then map unobstructed
    // photons onto their sub-pixel cells exactly (the f32 frame's 1e-7 skew moved jittered
    // photons near cell edges into the next pixel).
    let _ = up;
    let eye = eye.as_dvec3();
    let forward = forward.as_dvec3().normalize();
    let right = (right.as_dvec3() - forward * right.as_dvec3().dot(forward)).normalize();
    let up = right.cross(forward);
    let travel = opts.light().travel().as_dvec3();
    let d = DVec3::new(travel.dot(right), travel.dot(up), travel.dot(forward));
    if d.z < MIN_FORWARD as f64 {
        bail!(
            "the light must come from the viewer's side: light travelling against the view \
             direction cannot be propagated by the sweep (light direction makes {:.1}° with \
             the view direction; at most {:.1}° is supported)",
            d.z.clamp(-1.0, 1.0).acos().to_degrees(),
            (MIN_FORWARD as f64).acos().to_degrees()
        );
    }
    let z_l = (planes.first_depth - planes.spacing) as f64;
    let z_k = depth as f64;
    ensure!(
        depth.is_finite() && z_k > z_l,
        "depth {depth} must lie beyond the light's start plane at depth {z_l:.4} (one plane \
         spacing in front of the volume)"
    );
    let (w, h) = (opts.width as usize, opts.height as usize);
    let tanf = (camera.fov_y.to_radians() as f64 * 0.5).tan();
    let aspect = w as f64 / h as f64;
    let half_w = z_k * tanf * aspect;
    let half_h = z_k * tanf;
    let (px, py) = (2.0 * half_w / w as f64, 2.0 * half_h / h as f64);
    let k = popts.per_axis() as f64;
    let (dx, dy) = (px / k, py / k);
    let shift = DVec3::new(d.x / d.z, d.y / d.z, 0.0) * (z_k - z_l);
    // Launch rectangle: back-projections of the plane's corners and the box corners.
    let back = |q: DVec3| (q.x - d.x / d.z * (q.z - z_l), q.y - d.y / d.z * (q.z - z_l));
    let mut pts = Vec::new();
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        pts.push(back(DVec3::new(sx * half_w, sy * half_h, z_k)));
    }
    let half = field.half;
    for i in 0..8 {
        let c = DVec3::new(
            if i & 1 == 0 { -half.x } else { half.x },
            if i & 2 == 0 { -half.y } else { half.y },
            if i & 4 == 0 { -half.z } else { half.z },
        ) - eye;
        pts.push(back(DVec3::new(c.dot(right), c.dot(up), c.dot(forward))));
    }
    let (xmin, xmax) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (ymin, ymax) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    // Landing x of column i: -half_w + (i + 0.5) dx; launch x = landing - shift.x.
    // Landing y of row j: half_h - (j + 0.5) dy; launch y = landing - shift.y.
    let i0 = ((xmin + shift.x + half_w) / dx - 0.5).floor() as i64 - 1;
    let i1 = ((xmax + shift.x + half_w) / dx - 0.5).ceil() as i64 + 1;
    let j0 = ((half_h - shift.y - ymax) / dy - 0.5).floor() as i64 - 1;
    let j1 = ((half_h - shift.y - ymin) / dy - 0.5).ceil() as i64 + 1;
    let cols = (i1 - i0 + 1) as u64;
    let rows = (j1 - j0 + 1) as u64;
    ensure!(
        cols * rows <= 1 << 36,
        "{} photons are too many; use fewer photons per pixel or a smaller image",
        cols * rows
    );
    let step = popts.step as f64 * field.ref_step;
    // The work, estimated before any of it: each photon's straight path from the launch
    // plane to the target plane, in steps (refraction bends it, total reflection and
    // absorption end it early; the estimate is for the order of magnitude).
    let steps = (cols * rows) as f64 * ((z_k - z_l) / d.z / step).ceil().max(1.0);
    if let Some(max) = popts.max_steps {
        ensure!(
            steps <= max,
            "{} photons of about {:.0} steps each, {steps:.2e} RK4 steps in all, exceed the \
             limit of {max:.1e} (10¹² is about 40 min on 2 cores); use a larger --step, fewer \
             --photons-per-pixel or a smaller image, or raise it with --max-steps",
            cols * rows,
            steps / (cols * rows) as f64
        );
    }
    let colour = opts.light().colour.map(|c| c as f64);
    let cell = dx * dy;
    let target = Target {
        n: forward,
        c: z_k + forward.dot(eye),
    };
    let threads = crate::workers::count(popts.threads)?;
    let eta_launch = |p: DVec3| field.eta_w(p);

    #[derive(Default)]
    struct Acc {
        flux: Vec<[f64; 3]>,
        counts: Vec<u32>,
        landed: u64,
        outside: u64,
        absorbed: u64,
        backward: u64,
        steep: u64,
        lost: u64,
    }
    let next_row = AtomicUsize::new(0);
    let work = || {
        let mut acc = Acc {
            flux: vec![[0.0; 3]; w * h],
            counts: vec![0; w * h],
            ..Default::default()
        };
        loop {
            let r = next_row.fetch_add(1, Ordering::Relaxed) as u64;
            if r >= rows {
                break;
            }
            progress(r, rows);
            let j = j0 + r as i64;
            for c in 0..cols {
                let i = i0 + c as i64;
                let (ux, uy) = if popts.jitter {
                    let hsh = splitmix(
                        popts.seed ^ splitmix((j as u64) << 32 ^ (i as u64 & 0xffff_ffff)),
                    );
                    (uniform(hsh), uniform(splitmix(hsh)))
                } else {
                    (0.5, 0.5)
                };
                let lx = -half_w + (i as f64 + ux) * dx - shift.x;
                let ly = half_h - (j as f64 + uy) * dy - shift.y;
                let p = eye + right * lx + up * ly + forward * z_l;
                let v = travel * eta_launch(p);
                let t = field.trace(p, v, target, step, true, &mut |_, _, _, _, _| {});
                if t.min_forward < MIN_FORWARD as f64 {
                    acc.steep += 1;
                }
                match t.end {
                    End::Plane => {
                        let q = t.p - eye;
                        let ux = q.dot(right) / half_w * 0.5 + 0.5;
                        let uy = -q.dot(up) / half_h * 0.5 + 0.5;
                        let (fx, fy) = ((ux * w as f64).floor(), (uy * h as f64).floor());
                        if fx >= 0.0 && fy >= 0.0 && fx < w as f64 && fy < h as f64 {
                            let idx = fy as usize * w + fx as usize;
                            // The fluence's weight (PhotonOptions::plane_flux): the flux
                            // per unit area across the photon, relative to the launch's.
                            let weight = if popts.plane_flux {
                                1.0
                            } else {
                                d.z / (t.v.normalize().dot(forward)).max(0.1)
                            };
                            for (ch, c) in colour.iter().enumerate() {
                                acc.flux[idx][ch] += weight * c * cell * t.log_t[ch].exp();
                            }
                            acc.counts[idx] += 1;
                            acc.landed += 1;
                        } else {
                            acc.outside += 1;
                        }
                    }
                    End::Absorbed => acc.absorbed += 1,
                    End::Backward => acc.backward += 1,
                    End::Lost => acc.lost += 1,
                }
            }
        }
        acc
    };
    let parts: Vec<Acc> = crate::workers::run(threads, "photon", work)?;
    let mut total = Acc {
        flux: vec![[0.0; 3]; w * h],
        counts: vec![0; w * h],
        ..Default::default()
    };
    for a in parts {
        for (t, f) in total.flux.iter_mut().zip(&a.flux) {
            for ch in 0..3 {
                t[ch] += f[ch];
            }
        }
        for (t, c) in total.counts.iter_mut().zip(&a.counts) {
            *t += c;
        }
        total.landed += a.landed;
        total.outside += a.outside;
        total.absorbed += a.absorbed;
        total.backward += a.backward;
        total.steep += a.steep;
        total.lost += a.lost;
    }
    let area = px * py;
    let pixels = total
        .flux
        .iter()
        .map(|f| {
            [
                (f[0] / area) as f32,
                (f[1] / area) as f32,
                (f[2] / area) as f32,
                0.0,
            ]
        })
        .collect();
    Ok(PhotonImage {
        width: opts.width,
        height: opts.height,
        pixels,
        counts: total.counts,
        depth,
        photons_per_pixel: (k * k) as u32,
        photons: cols * rows,
        landed: total.landed,
        outside: total.outside,
        absorbed: total.absorbed,
        backward: total.backward,
        steep: total.steep,
        lost: total.lost,
        seconds: start.elapsed().as_secs_f64(),
        threads,
    })
}

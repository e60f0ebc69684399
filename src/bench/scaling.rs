//! `bench scaling`: how the sweep's cost grows with planes and covered pixels (a linear
//! fit per axis).

use super::*;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Point {
    pub planes: u32,
    pub pixels: u64,
    /// Mean pixels a plane shades (the `region` lever's rectangles; = pixels with
    /// `region=full`).
    #[serde(default)]
    pub shaded_pixels: f64,
    pub sweep_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Fit {
    /// sweep_ms ≈ intercept + slope · x
    pub slope: f64,
    pub intercept: f64,
    pub r2: f64,
}

/// Least-squares line through (x, y).
pub fn fit(x: &[f64], y: &[f64]) -> Result<Fit> {
    ensure!(x.len() == y.len() && x.len() >= 2, "a fit needs two points");
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    ensure!(sxx > 0.0, "a fit needs two different x values");
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ss_tot: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    let ss_res: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - intercept - slope * a).powi(2))
        .sum();
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        1.0
    };
    Ok(Fit {
        slope,
        intercept,
        r2,
    })
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ScalingReport {
    pub meta: Meta,
    pub scene: String,
    pub frames: u32,
    /// Varying the sample distance at a fixed viewport.
    pub by_planes: Vec<Point>,
    pub planes_fit: Fit,
    /// Varying the viewport at a fixed sample distance.
    pub by_pixels: Vec<Point>,
    pub pixels_fit: Fit,
}

/// Sweep time against plane count (sample distances `distances` at `side`²) and against
/// pixel count (viewports `sides` at the scene's sample distance), each point the mean of
/// `frames` frames after one warm-up.
pub fn scaling(
    ctx: &Context,
    scene: &Scene,
    data_dir: &Path,
    distances: &[f32],
    sides: &[u32],
    frames: u32,
    progress: bool,
) -> Result<ScalingReport> {
    ensure!(frames >= 1, "--frames must be at least 1");
    // Any scene `render` takes: a volume file's transfer functions may come from its data.
    let loaded = scene.load_all(data_dir, Some(upload::device_limits(ctx)))?;
    let mut renderer = Renderer::new(ctx, &loaded.volume, &loaded.tf)?;
    renderer.set_environment(loaded.env.as_ref())?;
    let pb = progress_bar(
        ((distances.len() + sides.len()) as u64) * (frames as u64 + 1),
        progress,
    );
    let mut measure = |opts: &RenderOptions| -> Result<Point> {
        let mut sum = 0.0;
        let mut planes = 0;
        let mut shaded = 1.0;
        for k in 0..=frames {
            let f = renderer.render(Model::Refract, &scene.camera, opts)?;
            pb.inc(1);
            if k > 0 {
                sum += f.timings.get("sweep").context("no timestamps")?;
            }
            planes = f.sweep.as_ref().map(|s| s.planes.count).unwrap_or(0);
            shaded = f.sweep.as_ref().map_or(1.0, |s| s.shaded_fraction);
        }
        let pixels = opts.width as u64 * opts.height as u64;
        Ok(Point {
            planes,
            pixels,
            shaded_pixels: shaded * pixels as f64,
            sweep_ms: sum / frames as f64,
        })
    };
    let base = scene.render_options()?;
    let mut by_planes = Vec::new();
    for &d in distances {
        let mut o = base.clone();
        o.sample_distance = d;
        o.validate()?;
        by_planes.push(measure(&o)?);
    }
    let mut by_pixels = Vec::new();
    for &side in sides {
        let mut o = base.clone();
        o.width = side;
        o.height = side;
        o.validate()?;
        by_pixels.push(measure(&o)?);
    }
    pb.finish_and_clear();
    let planes_fit = fit(
        &by_planes
            .iter()
            .map(|p| p.planes as f64)
            .collect::<Vec<_>>(),
        &by_planes.iter().map(|p| p.sweep_ms).collect::<Vec<_>>(),
    )?;
    let pixels_fit = fit(
        &by_pixels
            .iter()
            .map(|p| p.pixels as f64)
            .collect::<Vec<_>>(),
        &by_pixels.iter().map(|p| p.sweep_ms).collect::<Vec<_>>(),
    )?;
    Ok(ScalingReport {
        meta: meta(ctx),
        scene: scene.name.clone(),
        frames,
        by_planes,
        planes_fit,
        by_pixels,
        pixels_fit,
    })
}

/// How far the cost per plane and shaded pixel strays from its median over every point of
/// the report, in percent (most below, most above): how nearly the sweep's cost is
/// proportional to planes × shaded pixels (issue 16's goal: within ±15 %).
pub fn proportionality(r: &ScalingReport) -> Option<(f64, f64)> {
    let v: Vec<f64> = r
        .by_planes
        .iter()
        .chain(&r.by_pixels)
        .filter(|p| p.planes > 0 && p.shaded_pixels > 0.0)
        .map(|p| p.sweep_ms / (p.planes as f64 * p.shaded_pixels))
        .collect();
    let median = Stats::of(&v).ok()?.median;
    let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    Some((100.0 * (lo / median - 1.0), 100.0 * (hi / median - 1.0)))
}

pub fn scaling_markdown(r: &ScalingReport) -> String {
    let mut s = format!(
        "Device: {} ({}); scene {}; mean sweep GPU ms of {} frames per point\n\n",
        r.meta.device, r.meta.driver_info, r.scene, r.frames
    );
    s += "| Planes | Pixels | Shaded per plane | Sweep ms | ms per plane | ns per plane-pixel | ns per plane-shaded-pixel |\n|---:|---:|---:|---:|---:|---:|---:|\n";
    let per_shaded = |p: &Point| p.sweep_ms * 1e6 / (p.planes as f64 * p.shaded_pixels);
    for p in r.by_planes.iter().chain(&r.by_pixels) {
        s += &format!(
            "| {} | {} | {:.0} | {:.2} | {:.3} | {:.2} | {:.2} |\n",
            p.planes,
            p.pixels,
            p.shaded_pixels,
            p.sweep_ms,
            p.sweep_ms / p.planes as f64,
            p.sweep_ms * 1e6 / (p.planes as f64 * p.pixels as f64),
            per_shaded(p)
        );
    }
    if let Some(spread) = proportionality(r) {
        s += &format!(
            "\nCost per plane and shaded pixel: within {:+.1} % / {:+.1} % of its median over \
             all points (cost ∝ planes × shaded pixels would be 0 %)\n",
            spread.0, spread.1
        );
    }
    s += &format!(
        "\nAgainst planes (fixed pixels): {:.4} ms per plane + {:.2} ms, R² = {:.4}\n",
        r.planes_fit.slope, r.planes_fit.intercept, r.planes_fit.r2
    );
    s += &format!(
        "Against pixels (fixed sample distance): {:.4} ms per 1000 pixels + {:.2} ms, R² = {:.4}\n",
        r.pixels_fit.slope * 1000.0,
        r.pixels_fit.intercept,
        r.pixels_fit.r2
    );
    s
}

//! Environment maps behind the volume (thesis sect. 4.4, 5.3): equirectangular images, and
//! the host side of their summed-area table (built on the GPU by `render::sat`), so the
//! composite can average the map over the footprint of a pixel's refracted rays.
//!
//! Coordinates: column x covers longitude φ = 2π (x + 0.5) / width − π (−π at the left
//! edge, the seam at ±π), row y covers latitude θ = π/2 − π (y + 0.5) / height (+π/2, the
//! zenith, at the top). Directions: y up; φ = atan2(d.x, −d.z), so −z looks at the map's
//! centre column.

use std::path::Path;

use anyhow::{bail, ensure, Context as _, Result};

/// An equirectangular map in linear RGB (alpha 1), row-major, top row (zenith) first.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl EnvironmentMap {
    /// A map checked for shape (2:1) and finite values. Negative values within 1 % of the
    /// map's mean are set to 0 (one warning); anything more negative is refused. Lossy EXR
    /// files get a different rule, see [`EnvironmentMap::load`].
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>, origin: &str) -> Result<Self> {
        Self::checked(width, height, pixels, origin, None)
    }

    /// [`EnvironmentMap::new`], or with `lossy` (the name of the lossy compression the
    /// values went through) every negative value set to 0 and counted in one warning.
    fn checked(
        width: u32,
        height: u32,
        pixels: Vec<[f32; 4]>,
        origin: &str,
        lossy: Option<&str>,
    ) -> Result<Self> {
        ensure!(
            width >= 2 && height >= 1 && width == 2 * height,
            "{origin}: an equirectangular map must be twice as wide as high, this one is \
             {width}x{height}"
        );
        ensure!(
            pixels.len() == (width as usize) * (height as usize),
            "{origin}: {} pixels for {width}x{height}",
            pixels.len()
        );
        if let Some(i) = pixels.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            bail!(
                "{origin}: pixel ({}, {}) is {:?}, not a finite colour",
                i as u32 % width,
                i as u32 / width,
                pixels[i]
            );
        }
        // Lossy EXR codecs (DWAA/DWAB, B44, PXR24) ring below zero near bright pixels: by
        // -3394 in one CC0 DWAB map (issue 15), and OpenEXR decodes the same values.
        // Radiance is never negative, so in a lossy map every negative value is that ringing
        // and set to 0. In other maps only values within 1 % of the map's mean are taken
        // for rounding noise (of an editor's filter, say); anything more negative is not a
        // radiance map.
        let mean = pixels
            .iter()
            .map(|p| (p[0] + p[1] + p[2]) as f64)
            .sum::<f64>()
            / (3 * pixels.len()) as f64;
        let tolerance = match lossy {
            Some(_) => f32::NEG_INFINITY,
            None => -(0.01 * mean) as f32,
        };
        let mut pixels = pixels;
        let (mut fixed, mut lowest, mut at) = (0usize, 0f32, 0usize);
        for (i, p) in pixels.iter_mut().enumerate() {
            for c in &mut p[..3] {
                if *c < 0.0 {
                    ensure!(
                        *c >= tolerance,
                        "{origin}: pixel ({}, {}) has the negative value {c}, more than 1 % of \
                         the map's mean ({mean:.4}) below zero: not a radiance map",
                        i as u32 % width,
                        i as u32 / width
                    );
                    if *c < lowest {
                        (lowest, at) = (*c, i);
                    }
                    *c = 0.0;
                    fixed += 1;
                }
            }
        }
        if fixed > 0 {
            let (x, y) = (at as u32 % width, at as u32 / width);
            match lossy {
                Some(compression) => log::warn!(
                    "{origin}: {fixed} negative channel values (most negative {lowest} at pixel \
                     ({x}, {y})) set to 0: ringing of the lossy {compression} compression"
                ),
                None => log::warn!(
                    "{origin}: {fixed} slightly negative channel values (most negative \
                     {lowest:e} at pixel ({x}, {y}), within 1 % of the map's mean) set to 0"
                ),
            }
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// A constant colour.
    pub fn constant(width: u32, colour: [f32; 3]) -> Result<Self> {
        let height = (width / 2).max(1);
        let px = [colour[0], colour[1], colour[2], 1.0];
        Self::new(
            height * 2,
            height,
            vec![px; (height * 2 * height) as usize],
            "constant map",
        )
    }

    /// The built-in sky's width (`--env sky`, the viewer panel's "sky").
    pub const SKY_WIDTH: u32 = 1024;

    /// The default when no map is given, so nothing must be downloaded: a sky gradient with
    /// a sun and a checkered ground, `width` × `width / 2`.
    pub fn procedural(width: u32) -> Result<Self> {
        let height = (width / 2).max(1);
        let width = height * 2;
        let sun = [0.35f32, 0.55, -0.76];
        let sun_len = (sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]).sqrt();
        let shade = |x: f32, y: f32| -> [f32; 3] {
            let (phi, theta) = pixel_angles(width, height, x, y);
            let d = direction(phi, theta);
            if theta >= 0.0 {
                let t = theta / std::f32::consts::FRAC_PI_2;
                let horizon = [0.75, 0.8, 0.9];
                let zenith = [0.15, 0.3, 0.7];
                let cos_sun = (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]) / sun_len;
                let glow =
                    if cos_sun > 0.9995 { 40.0 } else { 0.0 } + 0.6 * cos_sun.max(0.0).powi(64);
                std::array::from_fn(|i| horizon[i] + (zenith[i] - horizon[i]) * t.sqrt() + glow)
            } else {
                // Ground plane at distance 1 below: checks of 0.25 units.
                let s = -1.0 / d[1];
                let (gx, gz) = ((d[0] * s / 0.25).floor(), (d[2] * s / 0.25).floor());
                let check = if (gx + gz).rem_euclid(2.0) < 1.0 {
                    0.6
                } else {
                    0.12
                };
                let fade = (-theta).sin().powf(0.3);
                [check * fade + 0.3 * (1.0 - fade); 3]
            }
        };
        // 4 x 4 samples per texel, so the distant checks do not alias into the map itself.
        let mut pixels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                let mut acc = [0.0f32; 3];
                for sy in 0..4 {
                    for sx in 0..4 {
                        let c = shade(
                            x as f32 + (sx as f32 + 0.5) / 4.0,
                            y as f32 + (sy as f32 + 0.5) / 4.0,
                        );
                        for i in 0..3 {
                            acc[i] += c[i] / 16.0;
                        }
                    }
                }
                pixels.push([acc[0], acc[1], acc[2], 1.0]);
            }
        }
        Self::new(width, height, pixels, "procedural map")
    }

    /// Load an equirectangular map: OpenEXR (.exr) and Radiance (.hdr) as linear, PNG/JPEG
    /// as sRGB. Errors name the file. NaN and infinity are refused. In an EXR whose R, G or
    /// B channel is lossy-compressed (DWAA, DWAB; B44, B44A for half floats; PXR24 for
    /// 32-bit floats) every negative value is set to 0 with one warning; elsewhere the rule
    /// of [`EnvironmentMap::new`] holds. A header that claims more pixels than the file can
    /// hold (see `decode_budget`) is refused before anything of that size is allocated.
    pub fn load(path: &Path) -> Result<Self> {
        let origin = path.display().to_string();
        if let Some(why) = crate::volume::formats::why_not_a_file(path) {
            bail!("environment map {origin}: {why}");
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "exr" => {
                check_exr_size(path, &origin)?;
                // On this thread (exr's decoding threads abort the process when a decoder
                // panics, as exr 1.74's B44 decoder does on corrupt data in debug builds),
                // with a panic turned into an error.
                let decode = || {
                    use exr::prelude::{ReadChannels as _, ReadLayers as _};
                    exr::prelude::read()
                        .no_deep_data()
                        .largest_resolution_level()
                        .rgba_channels(
                            |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
                            |(w, px): &mut (usize, Vec<[f32; 4]>),
                             pos,
                             (r, g, b, _a): (f32, f32, f32, f32)| {
                                px[pos.y() * *w + pos.x()] = [r, g, b, 1.0];
                            },
                        )
                        .first_valid_layer()
                        .all_attributes()
                        .non_parallel()
                        .from_file(path)
                };
                let img = std::panic::catch_unwind(std::panic::AssertUnwindSafe(decode))
                    .map_err(|_| {
                        anyhow::anyhow!(
                            "environment map {origin}: not a readable EXR: the decoder failed \
                             (corrupt data)"
                        )
                    })?
                    .map_err(|e| {
                        anyhow::anyhow!("environment map {origin}: not a readable EXR: {e}")
                    })?;
                let layer = img.layer_data;
                let compression = layer.encoding.compression;
                let (r, g, b, _) = &layer.channel_data.channels;
                let lossy = [r, g, b]
                    .iter()
                    .any(|c| !compression.is_lossless_for(c.sample_type));
                // "dwab compression" -> "DWAB"
                let name = compression.to_string().replace(" compression", "");
                let (_, pixels) = layer.channel_data.pixels;
                Self::checked(
                    layer.size.width() as u32,
                    layer.size.height() as u32,
                    pixels,
                    &origin,
                    lossy.then(|| name.to_uppercase()).as_deref(),
                )
            }
            "hdr" | "png" | "jpg" | "jpeg" => {
                let (w, h) = image::ImageReader::open(path)
                    .and_then(|r| r.with_guessed_format())
                    .map_err(image::ImageError::IoError)
                    .and_then(|r| r.into_dimensions())
                    .with_context(|| format!("environment map {origin}: not a readable image"))?;
                check_pixels(w as u64, h as u64, &origin)?;
                let img = open_image(path)
                    .with_context(|| format!("environment map {origin}: not a readable image"))?;
                let linear = ext == "hdr";
                let rgb = img.to_rgb32f();
                let (w, h) = rgb.dimensions();
                let pixels = rgb
                    .pixels()
                    .map(|p| {
                        let c = if linear { p.0 } else { p.0.map(srgb_to_linear) };
                        [c[0], c[1], c[2], 1.0]
                    })
                    .collect();
                Self::new(w, h, pixels, &origin)
            }
            other => bail!(
                "environment map {origin}: unknown extension '.{other}'; use .exr, .hdr, .png \
                 or .jpg"
            ),
        }
    }

    /// The key light of the map (`--light env`): its brightest region as one directional
    /// light. `None` for a map that is black everywhere.
    ///
    /// The peak is the largest radiance after a box blur of about 11° (so one hot pixel
    /// does not win over a sun disk, and a soft box counts as a whole); the region is
    /// every pixel within 25° of the peak whose luminance is at least half the blurred
    /// peak's. Its direction is the region's flux-weighted mean direction, its colour the
    /// irradiance it gives a surface facing it, Σ L Δω over the region (Δω the pixel's
    /// solid angle): in the units of the map's radiance, so a dim night map gives a dim
    /// light and the background seen behind the volume keeps the same scale.
    pub fn key_light(&self) -> Option<KeyLight> {
        use std::f64::consts::PI;
        let (w, h) = (self.width as usize, self.height as usize);
        let lum = |p: &[f32; 4]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        let y: Vec<f64> = self.pixels.iter().map(lum).collect();
        // Box blur, separable, wrapping around in longitude, clamped in latitude.
        let r = (w / 64).max(1);
        let mut across = vec![0.0; w * h];
        for row in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for dx in 0..=2 * r {
                    sum += y[row * w + (x + w + dx - r) % w];
                }
                across[row * w + x] = sum / (2 * r + 1) as f64;
            }
        }
        let (mut peak, mut at) = (0.0, (0, 0));
        for row in 0..h {
            for x in 0..w {
                let lo = row.saturating_sub(r);
                let hi = (row + r).min(h - 1);
                let sum: f64 = (lo..=hi).map(|yy| across[yy * w + x]).sum();
                let v = sum / (hi - lo + 1) as f64;
                if v > peak {
                    peak = v;
                    at = (x, row);
                }
            }
        }
        if peak <= 0.0 || !peak.is_finite() {
            return None;
        }
        let dir = |x: usize, row: usize| {
            let (phi, theta) =
                pixel_angles(self.width, self.height, x as f32 + 0.5, row as f32 + 0.5);
            (
                glam::DVec3::from(direction(phi, theta).map(f64::from)),
                theta as f64,
            )
        };
        let (centre, _) = dir(at.0, at.1);
        let cos_max = 25f64.to_radians().cos();
        let pixel_area = (2.0 * PI / w as f64) * (PI / h as f64);
        let (mut flux_dir, mut colour, mut solid_angle) = (glam::DVec3::ZERO, [0.0f64; 3], 0.0);
        let mut rest = [0.0f64; 3];
        for row in 0..h {
            for x in 0..w {
                let p = &self.pixels[row * w + x];
                let (d, theta) = dir(x, row);
                let dw = pixel_area * theta.cos();
                if y[row * w + x] < 0.5 * peak || d.dot(centre) < cos_max {
                    for c in 0..3 {
                        rest[c] += p[c] as f64 * dw;
                    }
                    continue;
                }
                for c in 0..3 {
                    colour[c] += p[c] as f64 * dw;
                }
                flux_dir += d * y[row * w + x] * dw;
                solid_angle += dw;
            }
        }
        let towards = if flux_dir.length() > 0.0 {
            flux_dir.normalize()
        } else {
            centre
        };
        Some(KeyLight {
            towards: towards.as_vec3().to_array(),
            colour: colour.map(|c| c as f32),
            solid_angle: solid_angle as f32,
            // The rest's mean radiance over the whole sphere (the region counted as dark).
            ambient: rest.map(|c| (c / (4.0 * PI)) as f32),
        })
    }

    /// Mean colour (f64 accumulation).
    pub fn mean(&self) -> [f32; 4] {
        let mut acc = [0f64; 4];
        for p in &self.pixels {
            for i in 0..4 {
                acc[i] += p[i] as f64;
            }
        }
        acc.map(|a| (a / self.pixels.len() as f64) as f32)
    }
}

/// The most bytes decoding a map file of `file_len` bytes may allocate for its pixels:
/// 64 MiB plus 4096 per byte of file (more than deflate's 1032:1 expands to once half
/// floats are widened to f32 RGBA). A header that claims more is refused before a buffer
/// of its size is allocated: a few hundred bytes could otherwise ask for gigabytes.
fn decode_budget(file_len: u64) -> u64 {
    (64u64 << 20).saturating_add(file_len.saturating_mul(4096))
}

/// Refuses an EXR whose header claims more pixels than [`decode_budget`] allows, or an RGB
/// layer that is not twice as wide as high (the reader allocates the whole image, and
/// buffers of whole lines, as soon as it has read the header).
fn check_exr_size(path: &Path, origin: &str) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| anyhow::anyhow!("environment map {origin}: not a readable EXR: {e}"))?;
    let len = std::fs::metadata(path)
        .with_context(|| format!("environment map {origin}"))?
        .len();
    for h in meta.headers.iter() {
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        let bytes = w as u128 * ht as u128 * 16;
        ensure!(
            bytes <= decode_budget(len) as u128,
            "environment map {origin}: not a readable EXR: its header says {w}x{ht} pixels \
             ({bytes} bytes as f32 RGBA), more than a file of {len} bytes can hold (corrupt?)"
        );
    }
    // The layer that will be read: the first with R, G and B channels.
    let rgb = |h: &&exr::meta::header::Header| {
        ["R", "G", "B"]
            .iter()
            .all(|n| h.channels.list.iter().any(|c| c.name == **n))
    };
    if let Some(h) = meta.headers.iter().find(rgb) {
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        check_pixels(w as u64, ht as u64, origin)?;
        ensure!(
            ht >= 1 && w == 2 * ht,
            "{origin}: an equirectangular map must be twice as wide as high, this one is \
             {w}x{ht}"
        );
    }
    Ok(())
}

/// The most pixels an environment map may have unless `REFRAKT_ENV_MAX_PIXELS` raises it:
/// 8192x4096. Loading one costs about 64 bytes per pixel on the host (the decoded file,
/// f32 RGBA, the summed-area table) and 32 on the device: 2 GiB and 1 GiB at the limit.
/// A 16384x8192 map (a 400 KB PNG can be one) took 70 s and 8.5 GB before the limit.
pub const DEFAULT_MAX_PIXELS: u64 = 8192 * 4096;

/// [`DEFAULT_MAX_PIXELS`], or `REFRAKT_ENV_MAX_PIXELS` when it is set to a number.
fn max_pixels() -> Result<u64> {
    match std::env::var("REFRAKT_ENV_MAX_PIXELS") {
        Ok(v) if !v.is_empty() => v.trim().parse::<u64>().map_err(|_| {
            anyhow::anyhow!(
                "REFRAKT_ENV_MAX_PIXELS={:?}: not a whole number of pixels",
                v.chars().take(40).collect::<String>()
            )
        }),
        _ => Ok(DEFAULT_MAX_PIXELS),
    }
}

/// Refuses, from the header, a map of more pixels than [`max_pixels`] allows: before
/// anything of its size is decoded or allocated.
fn check_pixels(w: u64, h: u64, origin: &str) -> Result<()> {
    let max = max_pixels()?;
    ensure!(
        w.saturating_mul(h) <= max,
        "environment map {origin}: {w}x{h} is {} Mpixels, more than the limit of {} Mpixels \
         (about 64 bytes per pixel on the host while loading); scale it down (2:1, e.g. \
         8192x4096) or raise the limit with REFRAKT_ENV_MAX_PIXELS={}",
        (w * h) as f64 / 1e6,
        max as f64 / 1e6,
        w * h
    );
    Ok(())
}

/// `image::open` with the decoder's buffer limited to [`decode_budget`] (and the crate's
/// default of 512 MiB).
fn open_image(path: &Path) -> image::ImageResult<image::DynamicImage> {
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    let mut reader = image::ImageReader::open(path)?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(decode_budget(len).min(limits.max_alloc.unwrap_or(u64::MAX)));
    reader.limits(limits);
    reader.decode()
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A map's brightest region as a directional light ([`EnvironmentMap::key_light`]), in
/// the map's own frame (before `--env-rotation`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyLight {
    /// Unit direction towards the region.
    pub towards: [f32; 3],
    /// Irradiance on a surface facing it (linear RGB, the map's units).
    pub colour: [f32; 3],
    /// The region's solid angle, steradians.
    pub solid_angle: f32,
    /// The rest of the map as an ambient level: its mean radiance over the sphere, ∫ L dω /
    /// 4π over the pixels outside the region. A white medium lit by it alone returns it,
    /// so a white object in a uniform map of radiance L is as bright as the map behind it
    /// (the furnace test: `tests/ambient_level.rs`). Linear RGB, the map's units.
    pub ambient: [f32; 3],
}

impl KeyLight {
    /// [`KeyLight::towards`] in the world, for a map turned by `degrees` about the
    /// vertical (the composite looks a world direction up in the map turned back by it).
    pub fn world_towards(&self, degrees: f32) -> [f32; 3] {
        let r = degrees.to_radians();
        let [x, y, z] = self.towards;
        [r.cos() * x + r.sin() * z, y, -r.sin() * x + r.cos() * z]
    }
}

/// (longitude, latitude) of a continuous pixel position.
pub fn pixel_angles(width: u32, height: u32, x: f32, y: f32) -> (f32, f32) {
    use std::f32::consts::{FRAC_PI_2, PI};
    (
        2.0 * PI * x / width as f32 - PI,
        FRAC_PI_2 - PI * y / height as f32,
    )
}

/// Unit direction of (longitude, latitude).
pub fn direction(phi: f32, theta: f32) -> [f32; 3] {
    [
        theta.cos() * phi.sin(),
        theta.sin(),
        -theta.cos() * phi.cos(),
    ]
}

/// A summed-area table read back to the host (tests, diagnostics).
pub struct SatReadback {
    pub table: Vec<[f32; 4]>,
    pub width: u32,
    pub height: u32,
    pub mean: [f32; 4],
}

impl SatReadback {
    /// Average of the map over the pixel box [x0, x1) × [y0, y1). A box with x0 > x1 wraps
    /// across the ±180° seam and is split in two; the composite shader will apply the
    /// same rule.
    pub fn box_average(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> [f64; 4] {
        // S over [0, x) × [0, y): zero on the empty edges.
        let s = |x: u32, y: u32| -> [f64; 4] {
            if x == 0 || y == 0 {
                [0.0; 4]
            } else {
                self.table[((y - 1) * self.width + (x - 1)) as usize].map(|v| v as f64)
            }
        };
        let sum = |a: u32, b: u32| -> [f64; 4] {
            let (p, q, r, t) = (s(b, y1), s(a, y1), s(b, y0), s(a, y0));
            std::array::from_fn(|i| p[i] - q[i] - r[i] + t[i])
        };
        let rows = (y1 - y0) as f64;
        let (total, area) = if x0 <= x1 {
            (sum(x0, x1), (x1 - x0) as f64 * rows)
        } else {
            let (a, b) = (sum(x0, self.width), sum(0, x1));
            (
                std::array::from_fn(|i| a[i] + b[i]),
                ((self.width - x0) + x1) as f64 * rows,
            )
        };
        std::array::from_fn(|i| total[i] / area + self.mean[i] as f64)
    }
}

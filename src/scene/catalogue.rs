//! The built-in scenes: procedural test volumes, the thesis stand-ins and the fetched
//! real scans, and where their data lives.

use super::*;

/// Procedural scenes: name, description, transfer-function preset.
pub const PROCEDURAL: &[(&str, &str, &str)] = &[
    (
        "sphere-on-floor",
        "glass sphere over a floor, one directional light (Eikonal Rendering's Fig. 7 validation scene; the quick demo)",
        "glass-floor",
    ),
    (
        "shell",
        "noisy spherical shell with a dense core over a ground plane (small supernova)",
        "supernova",
    ),
    ("sphere", "solid sphere of value 1, radius 0.35", "sphere-white"),
    ("box", "solid box of value 1", "sphere-white"),
    (
        "glass-floor",
        "same as sphere-on-floor (kept for scripts)",
        "glass-floor",
    ),
    (
        "wine-glass",
        "a wine glass holding wine, after thesis Fig. 6.3",
        "wine-glass",
    ),
];

/// A real scan fetched by `scripts/fetch-data`: name, file in the data directory, value
/// window, transfer-function preset, description.
pub type FetchedScene = (
    &'static str,
    &'static str,
    Option<(f32, f32)>,
    &'static str,
    &'static str,
);

pub const FETCHED: &[FetchedScene] = &[
    (
        "lung-ct",
        "ct/lung1_image.nrrd",
        Some((-1000.0, 1000.0)),
        "lung-ct",
        "CT of a lung (pyradiomics 3.1.0 test data, 512x512x48 int16, HU window -1000..1000)",
    ),
    (
        "mri-head",
        "mri/ch2.nii.gz",
        None,
        "mri-head",
        "MRI head template ch2 (mricron-data, 181x217x181 u8)",
    ),
];

/// The directory `scripts/fetch-data` fills: `$REFRAKT_DATA_DIR`, else
/// `~/.cache/refrakt/data`.
pub fn data_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("REFRAKT_DATA_DIR") {
        return PathBuf::from(d);
    }
    std::env::var_os("HOME")
        .map(|h| PathBuf::from(h).join(".cache/refrakt/data"))
        .unwrap_or_else(|| PathBuf::from("refrakt-data"))
}

pub use crate::light::default_light;

/// Every built-in scene name with a one-line description, for `--help` and errors.
pub fn builtin_names() -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = PROCEDURAL
        .iter()
        .map(|(n, d, _)| (n.to_string(), d.to_string()))
        .collect();
    for d in &standins::DATASETS {
        v.push((
            d.name.to_string(),
            format!(
                "thesis stand-in {}x{}x{}: {} (Fig. {})",
                d.dims[0], d.dims[1], d.dims[2], d.description, d.figure
            ),
        ));
    }
    for (n, _, _, _, d) in FETCHED {
        v.push((n.to_string(), format!("{d}; needs scripts/fetch-data")));
    }
    v
}

/// `<name>.<ext>` in `dir` for any supported volume format, if present.
pub fn original_in(dir: &Path, name: &str) -> Option<PathBuf> {
    let entries = std::fs::read_dir(dir).ok()?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.split('.').next() == Some(name) && n.contains('.'))
                && crate::volume::formats::is_volume_file(p)
        })
        .collect();
    found.sort();
    found.into_iter().next()
}

pub fn procedural_volume(kind: &str, n: u32) -> Result<Volume> {
    Ok(match kind {
        "shell" => procedural::shell_on_floor(n, 7)?,
        "sphere" => procedural::sphere(n, 0.35, 1.0)?,
        "box" => procedural::boxed(n, [0.3, 0.25, 0.2], 1.0)?,
        "glass-floor" | "sphere-on-floor" => procedural::sphere_on_floor(n)?,
        "wine-glass" => procedural::wine_glass(n)?,
        _ => {
            let names: Vec<&str> = PROCEDURAL.iter().map(|p| p.0).collect();
            bail!(
                "unknown procedural volume '{kind}' (known: {})",
                names.join(", ")
            )
        }
    })
}

impl Scene {
    pub fn builtin(name: &str) -> Result<Option<Scene>> {
        let mut s = Scene {
            name: name.to_string(),
            ..Default::default()
        };
        if let Some((kind, _, tf)) = PROCEDURAL.iter().find(|(n, _, _)| *n == name) {
            s.volume = VolumeSource::Procedural {
                kind: kind.to_string(),
                size: 128,
            };
            s.transfer = TransferSource::Named(tf.to_string());
            return Ok(Some(s));
        }
        if let Some((_, file, window, tf, _)) = FETCHED.iter().find(|f| f.0 == name) {
            s.volume = VolumeSource::Fetched {
                file: file.to_string(),
                window: *window,
            };
            s.transfer = TransferSource::Named(tf.to_string());
            match name {
                "lung-ct" => {
                    // Slices along z (world z). The scan's +y is posterior and world +y is
                    // up, so turn it 180° about z (x and y flipped: still a right-handed
                    // body, spine down). Look along the body axis, slightly from above.
                    s.flip = [true, true, false];
                    s.camera = Camera {
                        azimuth: 20.0,
                        elevation: 15.0,
                        distance: 1.8,
                        fov_y: 35.0,
                        target: Vec3::ZERO,
                    };
                }
                _ => {
                    s.camera = Camera {
                        azimuth: 35.0,
                        elevation: 15.0,
                        distance: 2.1,
                        fov_y: 35.0,
                        target: Vec3::ZERO,
                    };
                    s.clip = Some((Vec3::new(1.0, 0.0, 0.0), 0.0));
                }
            }
            return Ok(Some(s));
        }
        let Some(d) = standins::DATASETS.iter().find(|d| d.name == name) else {
            return Ok(None);
        };
        s.volume = VolumeSource::Standin {
            name: d.name.to_string(),
            scale: 1.0,
        };
        s.transfer = TransferSource::Named(
            match d.name {
                "glass" => "glass-scene",
                n => n,
            }
            .to_string(),
        );
        // The thesis' protocol: 768 x 768, sample distance 1.
        s.width = 768;
        s.height = 768;
        let cam = |azimuth, elevation, distance| Camera {
            azimuth,
            elevation,
            distance,
            fov_y: 35.0,
            target: Vec3::ZERO,
        };
        match d.name {
            "supernova" => s.camera = cam(30.0, 15.0, 2.1),
            "piggy-bank" => {
                s.camera = cam(25.0, 30.0, 1.9);
                s.softness = 1.5;
            }
            "glass" => s.camera = cam(20.0, 12.0, 1.9),
            "hand" => s.camera = cam(20.0, 55.0, 1.9),
            "head" => {
                s.camera = cam(40.0, 10.0, 2.0);
                // Thesis Fig. 6.6: opacity zero in one half, medium and refraction kept.
                s.clip = Some((Vec3::new(1.0, 0.0, 0.0), 0.0));
            }
            "water" => s.camera = cam(25.0, 28.0, 2.0),
            "ship" => s.camera = cam(55.0, 20.0, 2.0),
            "kiwi" => s.camera = cam(15.0, 25.0, 1.8),
            _ => {}
        }
        Ok(Some(s))
    }
}

//! Deterministic stand-ins for the eight data sets of the thesis' timing tables (Tables 6.1
//! and 6.2). The originals (a supernova simulation, CT and MRI scans, modelled scenes) are
//! not obtainable here, so each is replaced by a procedural volume **at the original's exact
//! resolution** with the structures its figure shows, so that the plane count and the
//! per-plane work of the benchmark match the thesis row by row. They are stand-ins: the
//! timings depend on resolution and viewport, not on the voxel values, but the images are
//! only "after" the thesis figures.
//!
//! Generation is seeded (integer hashing, no platform RNG), multi-threaded over z slabs,
//! and cached on disk as `<name>_<X>x<Y>x<Z>_uint8.raw` (open-scivis naming) so that the
//! 472 M voxels of the glass are paid for once. The raw file stays a plain raw file any
//! tool loads; beside it, `<raw file>.check` (a few lines of text, see [`Check`]) holds
//! the format tag, `GENERATOR_VERSION`, the name, the dimensions, the byte count and a
//! CRC-32 of the raw bytes. A cache whose check file is missing or names other
//! parameters, or whose bytes do not match (corrupt, truncated), is reported in one line
//! and regenerated (issue 33).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use glam::Vec3;

use super::{Volume, Voxels};

mod shapes;
use shapes::*;

/// Bumped whenever a generator changes, so stale cache files are not reused.
const GENERATOR_VERSION: u32 = 1;

/// One row of the thesis' timing tables.
#[derive(Clone, Copy, Debug)]
pub struct Dataset {
    /// Name used on the command line and in file names.
    pub name: &'static str,
    /// Name in the thesis' table.
    pub title: &'static str,
    /// Resolution as in the table.
    pub dims: [u32; 3],
    /// Which table and GPU: "6.1" (GTX 1070) or "6.2" (GTX 980).
    pub table: &'static str,
    pub thesis_gpu: &'static str,
    /// Mean render time over 100 frames at 768², sample distance 1, as printed.
    pub thesis_ms: f64,
    pub thesis_fps: f64,
    /// The figure the stand-in and its scene preset follow.
    pub figure: &'static str,
    pub description: &'static str,
}

pub const DATASETS: [Dataset; 8] = [
    Dataset {
        name: "supernova",
        title: "Supernova",
        dims: [432, 432, 432],
        table: "6.1",
        thesis_gpu: "NVIDIA GeForce GTX 1070",
        thesis_ms: 108.53,
        thesis_fps: 9.21,
        figure: "6.1",
        description: "turbulent shells with a dense core over a ground plane, purple outer medium",
    },
    Dataset {
        name: "piggy-bank",
        title: "Piggy bank",
        dims: [512, 512, 134],
        table: "6.1",
        thesis_gpu: "NVIDIA GeForce GTX 1070",
        thesis_ms: 157.04,
        thesis_fps: 6.37,
        figure: "6.2",
        description: "a curved ceramic shell (white, reflective) with a coin inside, yellow medium",
    },
    Dataset {
        name: "glass",
        title: "Glass",
        dims: [768, 768, 800],
        table: "6.1",
        thesis_gpu: "NVIDIA GeForce GTX 1070",
        thesis_ms: 217.20,
        thesis_fps: 4.60,
        figure: "6.3",
        description: "a stemmed glass holding liquid (solid of revolution), floor and back wall",
    },
    Dataset {
        name: "hand",
        title: "Hand",
        dims: [244, 124, 257],
        table: "6.1",
        thesis_gpu: "NVIDIA GeForce GTX 1070",
        thesis_ms: 52.77,
        thesis_fps: 18.95,
        figure: "6.8",
        description: "bones, vessels and soft tissue of a hand, each with its own refractive index",
    },
    Dataset {
        name: "head",
        title: "Head",
        dims: [512, 512, 333],
        table: "6.1",
        thesis_gpu: "NVIDIA GeForce GTX 1070",
        thesis_ms: 205.12,
        thesis_fps: 4.88,
        figure: "6.6",
        description: "skull, brain and soft tissue with air-filled sinuses and airway",
    },
    Dataset {
        name: "water",
        title: "Water",
        dims: [256, 256, 128],
        table: "6.2",
        thesis_gpu: "NVIDIA GeForce GTX 980",
        thesis_ms: 327.31,
        thesis_fps: 3.05,
        figure: "6.4",
        description: "water with a wavy surface over a floor, blue-green medium",
    },
    Dataset {
        name: "ship",
        title: "Ship",
        dims: [256, 256, 385],
        table: "6.2",
        thesis_gpu: "NVIDIA GeForce GTX 980",
        thesis_ms: 443.69,
        thesis_fps: 2.25,
        figure: "6.5",
        description: "a ship model inside a refractive blue block (total internal reflection)",
    },
    Dataset {
        name: "kiwi",
        title: "Kiwi",
        dims: [256, 256, 128],
        table: "6.2",
        thesis_gpu: "NVIDIA GeForce GTX 980",
        thesis_ms: 155.15,
        thesis_fps: 6.45,
        figure: "6.7",
        description: "a kiwifruit slice: skin, flesh, a ring of seeds, a pale core",
    },
];

pub fn dataset(name: &str) -> Result<&'static Dataset> {
    DATASETS.iter().find(|d| d.name == name).with_context(|| {
        let names: Vec<&str> = DATASETS.iter().map(|d| d.name).collect();
        format!(
            "unknown thesis data set '{name}' (known: {})",
            names.join(", ")
        )
    })
}

/// The resolution at `scale` (benchmark `--scale`): every axis scaled and rounded, at
/// least 2 voxels.
pub fn scaled_dims(dims: [u32; 3], scale: f64) -> Result<[u32; 3]> {
    check_scale(scale)?;
    let scaled = dims.map(|d| (d as f64 * scale).round() as u32);
    if scaled.iter().any(|&d| d < 2) {
        // Not raised to 2 quietly: a report would name a scale it did not measure.
        let smallest = dims.iter().copied().min().unwrap_or(1).max(1);
        bail!(
            "scale {scale} leaves {}x{}x{} voxels of {}x{}x{}, fewer than 2 along an axis; \
             this data set needs a scale of at least {:.4}",
            scaled[0],
            scaled[1],
            scaled[2],
            dims[0],
            dims[1],
            dims[2],
            1.5 / smallest as f64
        );
    }
    Ok(scaled)
}

/// A stand-in scale's own check: a number in (0, 4].
pub fn check_scale(scale: f64) -> Result<()> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 4.0) {
        bail!("scale {scale} must be a number in (0, 4]");
    }
    Ok(())
}

/// Where generated stand-ins are cached: `$REFRAKT_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/refrakt`, else `~/.cache/refrakt`; stand-ins go to `standins/` in it.
/// An empty variable counts as unset (`REFRAKT_CACHE_DIR=""` once cached stand-ins in the
/// working folder).
pub fn cache_dir() -> PathBuf {
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    let base = if let Some(d) = var("REFRAKT_CACHE_DIR") {
        PathBuf::from(d)
    } else if let Some(d) = var("XDG_CACHE_HOME") {
        PathBuf::from(d).join("refrakt")
    } else if let Some(h) = var("HOME") {
        PathBuf::from(h).join(".cache/refrakt")
    } else {
        std::env::temp_dir().join("refrakt-cache")
    };
    base.join("standins")
}

/// The cache file of a stand-in at `dims`.
pub fn cache_file(dir: &Path, name: &str, dims: [u32; 3]) -> PathBuf {
    dir.join(format!(
        "{name}_{}x{}x{}_uint8.v{GENERATOR_VERSION}.raw",
        dims[0], dims[1], dims[2]
    ))
}

/// The check file beside a cached stand-in: the raw file's name with `.check` appended.
pub fn check_file(raw: &Path) -> PathBuf {
    let mut name = raw.as_os_str().to_owned();
    name.push(".check");
    PathBuf::from(name)
}

/// The first line of a check file.
const CHECK_TAG: &str = "refrakt stand-in check 1";

/// What a stand-in's check file records (text, one `key value` per line after the tag):
///
/// ```text
/// refrakt stand-in check 1
/// generator 1
/// name hand
/// dims 244 124 257
/// bytes 7775712
/// crc32 1a2b3c4d
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    pub generator: u32,
    pub name: String,
    pub dims: [u32; 3],
    pub bytes: u64,
    pub crc32: u32,
}

impl Check {
    /// The check of `voxels`, the stand-in `name` at `dims` of this build's generators.
    pub fn of(name: &str, dims: [u32; 3], voxels: &[u8]) -> Self {
        Self {
            generator: GENERATOR_VERSION,
            name: name.to_string(),
            dims,
            bytes: voxels.len() as u64,
            crc32: crc32fast::hash(voxels),
        }
    }

    pub fn to_text(&self) -> String {
        let [x, y, z] = self.dims;
        format!(
            "{CHECK_TAG}\ngenerator {}\nname {}\ndims {x} {y} {z}\nbytes {}\ncrc32 {:08x}\n",
            self.generator, self.name, self.bytes, self.crc32
        )
    }

    /// Parses [`Check::to_text`]'s output; the error says what is wrong.
    pub fn parse(text: &str) -> Result<Self> {
        let mut lines = text.lines();
        if lines.next() != Some(CHECK_TAG) {
            bail!("the check file does not start with \"{CHECK_TAG}\"");
        }
        let mut field = |key: &str| -> Result<&str> {
            match lines.next().and_then(|l| l.strip_prefix(key)) {
                Some(v) if v.starts_with(' ') => Ok(v.trim()),
                _ => bail!("the check file has no '{key}' line where expected"),
            }
        };
        let bad = |key: &str| format!("the check file's '{key}' is not a number");
        let generator = field("generator")?
            .parse()
            .with_context(|| bad("generator"))?;
        let name = field("name")?.to_string();
        let d: Vec<u32> = field("dims")?
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .with_context(|| bad("dims"))?;
        let dims: [u32; 3] = d
            .try_into()
            .map_err(|_| anyhow::anyhow!("the check file's 'dims' are not three numbers"))?;
        let bytes = field("bytes")?.parse().with_context(|| bad("bytes"))?;
        let crc32 = u32::from_str_radix(field("crc32")?, 16).with_context(|| bad("crc32"))?;
        Ok(Self {
            generator,
            name,
            dims,
            bytes,
            crc32,
        })
    }
}

/// The cached voxels of `name` at `dims` if `raw` and its check file agree with each other
/// and with this build; `Ok(None)` when nothing is cached (no raw file); else the reason.
fn read_cached(raw: &Path, name: &str, dims: [u32; 3]) -> Result<Option<Vec<u8>>> {
    let bytes = match std::fs::read(raw) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => bail!("cannot read it: {e}"),
    };
    let check_path = check_file(raw);
    let text = match std::fs::read(&check_path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            bail!("no check file ({} is missing)", file_name(&check_path))
        }
        Err(e) => bail!("cannot read {}: {e}", file_name(&check_path)),
    };
    let check = Check::parse(&String::from_utf8_lossy(&text))?;
    let want = Check::of(name, dims, &[]);
    if check.generator != want.generator {
        bail!(
            "made by generator version {}, this build's is {}",
            check.generator,
            want.generator
        );
    }
    if check.name != want.name || check.dims != want.dims {
        let [x, y, z] = check.dims;
        bail!(
            "the check file is for {} at {x}x{y}x{z}",
            check.name.chars().take(40).collect::<String>()
        );
    }
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    if check.bytes != n {
        bail!("the check file says {} bytes, expected {n}", check.bytes);
    }
    if bytes.len() as u64 != n {
        bail!("{} bytes, expected {n} (truncated or padded)", bytes.len());
    }
    let crc = crc32fast::hash(&bytes);
    if crc != check.crc32 {
        bail!(
            "corrupt: the voxels do not match their checksum (CRC-32 {crc:08x}, the check \
             file says {:08x})",
            check.crc32
        );
    }
    Ok(Some(bytes))
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// The stand-in `name` at `dims`, from the cache in `dir` when it is there and passes its
/// check (see the module documentation), otherwise generated and written to it: the raw
/// file, then its check file, each atomically (an interrupted run leaves no partial file,
/// and a raw file without its check is regenerated). A cache that fails the check is
/// reported in one line ("stand-in cache FILE: REASON; regenerating"). Returns the volume
/// and whether it came from the cache.
pub fn load_or_generate(name: &str, dims: [u32; 3], dir: &Path) -> Result<(Volume, bool)> {
    dataset(name)?;
    let file = cache_file(dir, name, dims);
    match read_cached(&file, name, dims) {
        Ok(Some(bytes)) => return Ok((Volume::new(dims, [1.0; 3], Voxels::U8(bytes))?, true)),
        Ok(None) => {}
        Err(e) => log::warn!("stand-in cache {}: {e:#}; regenerating", file.display()),
    }
    let vol = generate(name, dims)?;
    std::fs::create_dir_all(dir)
        .with_context(|| format!("creating the stand-in cache {}", dir.display()))?;
    let Voxels::U8(bytes) = &vol.voxels else {
        unreachable!("stand-ins are u8")
    };
    crate::files::write_atomically(&file, bytes)?;
    let check = Check::of(name, dims, bytes);
    crate::files::write_atomically(&check_file(&file), check.to_text().as_bytes())?;
    Ok((vol, false))
}

/// Generates the stand-in `name` at `dims` (no cache).
pub fn generate(name: &str, dims: [u32; 3]) -> Result<Volume> {
    let f: &(dyn Fn(Vec3, f32) -> f32 + Sync) = match name {
        "supernova" => &supernova,
        "piggy-bank" => &piggy_bank,
        "glass" => &glass,
        "hand" => &hand,
        "head" => &head,
        "water" => &water,
        "ship" => &ship,
        "kiwi" => &kiwi,
        _ => {
            dataset(name)?;
            unreachable!()
        }
    };
    Volume::new(dims, [1.0; 3], Voxels::U8(fill(dims, f)?))
}

/// Evaluates `f(p, voxel)` at every voxel centre, p in box coordinates (the longest side
/// spans [-0.5, 0.5], the volume is centred on the origin, y up), `voxel` the side of one
/// voxel in those units; quantised to u8. Threads take whole z slices.
pub fn fill(dims: [u32; 3], f: &(dyn Fn(Vec3, f32) -> f32 + Sync)) -> Result<Vec<u8>> {
    let n = dims
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d as usize))
        .context("volume dimensions overflow")?;
    let longest = dims.iter().cloned().max().unwrap_or(1) as f32;
    let voxel = 1.0 / longest;
    let half = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * (0.5 * voxel);
    let slice = dims[0] as usize * dims[1] as usize;
    let mut out = vec![0u8; n];
    let threads = std::thread::available_parallelism()
        .map(|t| t.get())
        .unwrap_or(1)
        .min(dims[2] as usize)
        .max(1);
    let per = (dims[2] as usize).div_ceil(threads);
    std::thread::scope(|s| {
        for (t, chunk) in out.chunks_mut(per * slice).enumerate() {
            s.spawn(move || {
                for (i, v) in chunk.iter_mut().enumerate() {
                    let z = t * per + i / slice;
                    let y = (i % slice) / dims[0] as usize;
                    let x = i % dims[0] as usize;
                    let p =
                        Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) * voxel - half;
                    *v = (f(p, voxel).clamp(0.0, 1.0) * 255.0).round() as u8;
                }
            });
        }
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_dataset_generates_at_a_small_scale_and_is_deterministic() {
        for d in &DATASETS {
            let dims = scaled_dims(d.dims, 0.08).unwrap();
            let a = generate(d.name, dims).unwrap();
            let b = generate(d.name, dims).unwrap();
            assert_eq!(a, b, "{} is not deterministic", d.name);
            let Voxels::U8(v) = &a.voxels else { panic!() };
            let filled = v.iter().filter(|&&x| x > 20).count();
            assert!(
                filled > v.len() / 50 && filled < v.len(),
                "{}: {filled} of {} voxels filled",
                d.name,
                v.len()
            );
        }
    }

    #[test]
    fn thread_split_covers_every_voxel() {
        // Odd sizes so the last thread's chunk is short.
        let dims = [5, 3, 7];
        let v = fill(dims, &|p, _| p.z + 0.5).unwrap();
        let longest = 7.0;
        for z in 0..7 {
            let expect = (((z as f32 + 0.5) / longest) * 255.0).round() as u8;
            assert!(v[z * 15..(z + 1) * 15].iter().all(|&x| x == expect));
        }
    }

    #[test]
    fn cache_round_trip_and_bad_scale() {
        let dir = tempfile::tempdir().unwrap();
        let dims = [20, 10, 21];
        let (a, cached) = load_or_generate("hand", dims, dir.path()).unwrap();
        assert!(!cached);
        let (b, cached) = load_or_generate("hand", dims, dir.path()).unwrap();
        assert!(cached);
        assert_eq!(a, b);
        assert!(scaled_dims([4, 4, 4], 0.0).is_err());
        assert!(scaled_dims([4, 4, 4], f64::NAN).is_err());
        // Too small for a side of 2: refused, not raised to 2.
        assert_eq!(scaled_dims([124, 256, 256], 0.0121).unwrap(), [2, 3, 3]);
        assert!(scaled_dims([124, 256, 256], 0.012).is_err());
        assert!(load_or_generate("teapot", dims, dir.path()).is_err());
    }

    #[test]
    fn a_cache_that_fails_its_check_is_regenerated() {
        let dir = tempfile::tempdir().unwrap();
        let dims = [20, 10, 21];
        let (clean, _) = load_or_generate("hand", dims, dir.path()).unwrap();
        let raw = cache_file(dir.path(), "hand", dims);
        let check = check_file(&raw);
        let (raw0, check0) = (std::fs::read(&raw).unwrap(), std::fs::read(&check).unwrap());
        let text = String::from_utf8(check0.clone()).unwrap();
        assert_eq!(Check::parse(&text).unwrap(), Check::of("hand", dims, &raw0));
        assert!(text.starts_with(CHECK_TAG), "{text}");
        let n = raw0.len();
        let mut quarter = raw0.clone();
        quarter[..n / 4].fill(255);
        let cases: Vec<(Vec<u8>, Option<String>, &str)> = vec![
            (quarter, Some(text.clone()), "checksum"),
            (vec![0; n], Some(text.clone()), "checksum"),
            (raw0[..n - 1].to_vec(), Some(text.clone()), "truncated"),
            (raw0.clone(), None, "no check file"),
            (
                raw0.clone(),
                Some(text.replace("generator 1", "generator 2")),
                "generator",
            ),
            (
                raw0.clone(),
                Some(text.replace("name hand", "name kiwi")),
                "kiwi",
            ),
            (
                raw0.clone(),
                Some(text.replace("dims 20", "dims 21")),
                "21x10x21",
            ),
            (
                raw0.clone(),
                Some(text.replace("bytes ", "bytes 1")),
                "bytes",
            ),
            (raw0.clone(), Some("garbage".into()), "does not start"),
        ];
        for (bytes, check_text, reason) in cases {
            std::fs::write(&raw, &bytes).unwrap();
            match &check_text {
                Some(t) => std::fs::write(&check, t).unwrap(),
                None => std::fs::remove_file(&check).unwrap(),
            }
            let e = format!("{:#}", read_cached(&raw, "hand", dims).unwrap_err());
            assert!(e.contains(reason), "{reason}: {e}");
            let (v, cached) = load_or_generate("hand", dims, dir.path()).unwrap();
            assert!(!cached, "{reason}: used");
            assert_eq!(v, clean, "{reason}");
            assert_eq!(std::fs::read(&raw).unwrap(), raw0, "{reason}");
            assert_eq!(std::fs::read(&check).unwrap(), check0, "{reason}");
            assert!(load_or_generate("hand", dims, dir.path()).unwrap().1);
        }
        // Nothing cached: no reason, just generated.
        std::fs::remove_file(&raw).unwrap();
        assert!(read_cached(&raw, "hand", dims).unwrap().is_none());
    }
}

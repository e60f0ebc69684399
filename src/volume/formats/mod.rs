//! Volume file loaders: raw, NRRD, NIfTI-1, MetaImage, VTK XML ImageData and DICOM series.
//!
//! One entry point, [`load_volume`], picks the format from the path (a directory is a DICOM
//! series; otherwise the extension) or reads a raw file when [`LoadOptions::raw`] gives its
//! layout. [`is_volume_file`] tells a volume from a scene file by the same rules, without
//! reading any voxel data. `docs/FORMATS.md` lists what each format supports.
//!
//! # Value mapping
//!
//! The renderer uploads u8 and u16 voxels as UNORM textures and maps f32 voxels onto [0,1]
//! through [`Volume::range`] (`None`: the data's own minimum and maximum). The loaders
//! therefore produce:
//!
//! - **u8 / u16 data** (NRRD `uchar`/`ushort`, NIfTI `uint8`/`uint16`, MetaImage
//!   `MET_UCHAR`/`MET_USHORT`, VTI `UInt8`/`UInt16`, raw `uint8`/`uint16`, DICOM unsigned
//!   8/16-bit without rescaling): kept as [`Voxels::U8`] / [`Voxels::U16`], unchanged.
//! - **everything else** (signed integers, 32-bit integers, f32, f64, and any data that a
//!   NIfTI `scl_slope`/`scl_inter` or a DICOM `RescaleSlope`/`RescaleIntercept` changes):
//!   [`Voxels::F32`] holding the values themselves (after rescaling; CT comes out in
//!   Hounsfield units), with `range` = [`LoadOptions::window`] when given, else `None`
//!   (data min/max at upload).
//! - **a window given for u8 / u16 data**: converted to [`Voxels::F32`] with `range` = the
//!   window as well, so the window always means "these values map to 0 and 1".
//!
//! Nothing is clamped by the loaders. Values outside a window end up outside [0,1] in the
//! f32 texture; what the renderer does with them is the renderer's business. f64 values are
//! rounded to the nearest f32 and 32-bit integers above 2^24 lose their low bits (the
//! texture is f32 anyway); an f64 value beyond the f32 range becomes infinite and the load
//! fails ([`Volume::validate`] rejects non-finite voxels, as it does NaN in float files).
//!
//! Spacing comes from [`LoadOptions::spacing`] if given, else [`RawLayout::spacing`] (raw
//! files), else the file's header, else 1 along every axis. Orientation (NRRD `space
//! directions`, NIfTI qform/sform, DICOM `ImageOrientationPatient`) gives voxel sizes,
//! slice order and [`Volume::axes`] (the patient directions of the voxel axes): the voxels
//! stay in file order, x fastest; [`Volume::turn_upright`] turns them when asked.
//!
//! # Errors
//!
//! Every error is one line that starts with the path given and says why, e.g.
//! `scan.nhdr: data file 'scan.raw' is 1000 bytes, header says 2000 bytes`. No input
//! panics: sizes are computed with checked arithmetic and checked against the bytes really
//! present before anything of that size is allocated (compressed streams are read with a
//! limit of the size the header states, so a lying header costs at most the data that is
//! really there).

mod dicom;
mod files;
mod metaimage;
mod nifti;
mod nrrd;
mod raw;
mod vti;

use std::io::Read;
use std::path::Path;

use anyhow::{anyhow, bail, ensure, Result};

pub use files::why_not_a_file;
pub(crate) use files::{file_kind, read_file, read_file_at_most, read_promised};

use super::{Volume, Voxels};

/// How to read a volume file. `Default` reads everything from the file itself.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Read the file as headerless raw data with this layout, whatever its name. Without
    /// it, a `.raw` file must be named `<name>_<X>x<Y>x<Z>_<type>.raw`.
    pub raw: Option<RawLayout>,
    /// Values mapped to 0 and 1 on upload, e.g. `(-1000.0, 2000.0)` for CT in Hounsfield
    /// units. Makes the volume f32 (see the module doc).
    pub window: Option<(f32, f32)>,
    /// Voxel size along x, y, z; overrides the file's.
    pub spacing: Option<[f32; 3]>,
    /// What the device can hold. Given, every loader refuses a volume beyond it from the
    /// header, before reading or allocating its data.
    pub limits: Option<DeviceLimits>,
}

/// The device limits a volume must fit (plain numbers, read from a Vulkan device by
/// `render::upload::device_limits`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceLimits {
    /// `maxImageDimension3D`.
    pub max_3d_extent: u32,
    /// The largest device-local heap, in bytes.
    pub bytes_available: Option<u64>,
}

/// Layout of a headerless raw file: little-endian samples, x fastest, then y, then z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawLayout {
    pub dims: [u32; 3],
    pub kind: ScalarKind,
    pub spacing: Option<[f32; 3]>,
}

/// Sample types of raw files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarKind {
    U8,
    U16,
    I16,
    F32,
}

impl ScalarKind {
    /// Parses the names used in open-scivis file names and on command lines:
    /// `uint8`/`u8`, `uint16`/`u16`, `int16`/`i16`, `float32`/`f32`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "uint8" | "u8" => ScalarKind::U8,
            "uint16" | "u16" => ScalarKind::U16,
            "int16" | "i16" => ScalarKind::I16,
            "float32" | "f32" => ScalarKind::F32,
            _ => return None,
        })
    }

    pub fn size(self) -> usize {
        self.sample().size()
    }

    fn sample(self) -> Sample {
        match self {
            ScalarKind::U8 => Sample::U8,
            ScalarKind::U16 => Sample::U16,
            ScalarKind::I16 => Sample::I16,
            ScalarKind::F32 => Sample::F32,
        }
    }
}

/// Loads a volume file (or a DICOM series directory). See the module doc for the formats,
/// the value mapping and the errors.
pub fn load_volume(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    load_inner(path, opts).map_err(|e| {
        let reason = format!("{e:#}").replace(['\n', '\r'], " ");
        anyhow!("{}: {reason}", path.display())
    })
}

fn load_inner(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    if let Some((lo, hi)) = opts.window {
        ensure!(
            lo.is_finite() && hi.is_finite() && lo < hi && (hi - lo).is_finite(),
            "window ({lo}, {hi}) must be finite with lo < hi (and hi − lo finite)"
        );
    }
    if let Some(s) = opts.spacing {
        ensure!(
            s.iter().all(|x| x.is_finite() && *x > 0.0),
            "spacing {s:?} must be finite and positive"
        );
    }
    // A FIFO, socket or device would block or never end: only regular files (and
    // directories, for DICOM series) are read.
    let meta = std::fs::metadata(path).map_err(|e| anyhow!("cannot read: {e}"))?;
    ensure!(
        meta.is_file() || meta.is_dir(),
        "is not a regular file or a directory ({})",
        file_kind(&meta)
    );
    let volume = if let Some(layout) = &opts.raw {
        ensure!(!path.is_dir(), "is a directory, not a raw file");
        // A layout describes a headerless file: a file with a header of its own would be
        // read as bytes, its header taken for voxels.
        if let Some(kind) = Format::of(path).and_then(|f| f.header) {
            bail!(
                "is {kind} file, whose header gives its size and voxel type: a raw layout \
                 (--dims and --type, or dims and type in a scene) is for headerless raw \
                 files only; drop it"
            );
        }
        raw::load(path, layout, opts)?
    } else if path.is_dir() {
        dicom::load_series(path, opts)?
    } else {
        match Format::of(path) {
            Some(format) => (format.load)(path, opts)?,
            None if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("dcm")) =>
            {
                bail!("a single DICOM file: load the directory that holds its series")
            }
            None => bail!(
                "unknown volume format (known: {}, or a directory holding a DICOM series)",
                known_extensions().join(", ")
            ),
        }
    };
    volume.validate()?;
    Ok(volume)
}

/// True for the paths [`load_volume`] reads without a raw layout: files named `.raw`,
/// `.nrrd`, `.nhdr`, `.nii`, `.nii.gz`, `.mhd`, `.mha`, `.vti` (any case), and directories
/// that hold a DICOM file (named `.dcm`, or with the `DICM` marker; the first 64 entries
/// are looked at). Reads no voxel data.
pub fn is_volume_file(path: &Path) -> bool {
    if path.is_dir() {
        return dicom::looks_like_series_dir(path);
    }
    Format::of(path).is_some()
}

/// Checks that a volume of `dims` fits the device: every side at most `max_3d_extent`
/// (Vulkan's `maxImageDimension3D`) and, when `bytes_available` is given, the texture at
/// 4 bytes per voxel (the largest texel the renderer uploads, R32_SFLOAT) within it. Use
/// [`check_volume_limits`] to count the volume's real texel size.
pub fn check_limits(
    dims: [u32; 3],
    max_3d_extent: u32,
    bytes_available: Option<u64>,
) -> Result<()> {
    check_limits_texel(dims, 4, max_3d_extent, bytes_available)
}

/// [`check_limits`] with the texel size of `volume`'s voxels (1, 2 or 4 bytes).
pub fn check_volume_limits(
    volume: &Volume,
    max_3d_extent: u32,
    bytes_available: Option<u64>,
) -> Result<()> {
    let texel = match volume.voxels {
        Voxels::U8(_) => 1,
        Voxels::U16(_) => 2,
        Voxels::F32(_) => 4,
    };
    check_limits_texel(volume.dims, texel, max_3d_extent, bytes_available)
}

pub(crate) fn check_limits_texel(
    dims: [u32; 3],
    texel_bytes: u64,
    max_3d_extent: u32,
    bytes_available: Option<u64>,
) -> Result<()> {
    let [x, y, z] = dims;
    ensure!(
        dims.iter().all(|&d| d > 0),
        "volume {x}x{y}x{z} has a zero dimension"
    );
    for (axis, &d) in ["x", "y", "z"].iter().zip(&dims) {
        ensure!(
            d <= max_3d_extent,
            "volume {x}x{y}x{z} is {d} voxels along {axis}, more than the device's \
             maxImageDimension3D limit of {max_3d_extent}"
        );
    }
    if let Some(avail) = bytes_available {
        // u32^3 * 4 < 2^98: use u128 so this can never overflow.
        let need = x as u128 * y as u128 * z as u128 * texel_bytes as u128;
        ensure!(
            need <= avail as u128,
            "volume {x}x{y}x{z} needs {need} bytes of texture ({texel_bytes} per voxel), more \
             than the {avail} bytes available on the device"
        );
    }
    Ok(())
}

/// A file format a volume is read from, by its name's ending (DICOM series, read from a
/// directory, are not in this list: see [`load_volume`]). To add a format: a module
/// here with its `load`, one entry in [`FORMATS`], a row in docs/FORMATS.md's table
/// (`tests/formats.rs` checks that every extension here has one, and that the entry
/// loads what it names), and its tests in tests/formats.rs.
#[derive(Clone, Copy, Debug)]
pub struct Format {
    /// As docs/FORMATS.md names it.
    pub name: &'static str,
    /// File-name endings, lower case, with the dot (a name must be longer than it).
    pub extensions: &'static [&'static str],
    /// "is <header> file": what a raw layout given for such a file is refused as (a
    /// file with a header of its own); None for headerless raw files.
    pub header: Option<&'static str>,
    load: fn(&Path, &LoadOptions) -> Result<Volume>,
}

/// Every format read by its file name, in the order the names are tried.
pub const FORMATS: [Format; 5] = [
    Format {
        name: "raw",
        extensions: &[".raw"],
        header: None,
        load: raw::load_named,
    },
    Format {
        name: "NRRD",
        extensions: &[".nrrd", ".nhdr"],
        header: Some("an NRRD"),
        load: nrrd::load,
    },
    Format {
        name: "NIfTI-1",
        extensions: &[".nii", ".nii.gz"],
        header: Some("a NIfTI"),
        load: nifti::load,
    },
    Format {
        name: "MetaImage",
        extensions: &[".mhd", ".mha"],
        header: Some("a MetaImage"),
        load: metaimage::load,
    },
    Format {
        name: "VTK XML ImageData",
        extensions: &[".vti"],
        header: Some("a VTK image (.vti)"),
        load: vti::load,
    },
];

/// Every file-name ending [`FORMATS`] reads, in order.
pub fn known_extensions() -> Vec<&'static str> {
    FORMATS
        .iter()
        .flat_map(|f| f.extensions.iter().copied())
        .collect()
}

/// The JSON files beside a raw file that may state its spacing (see `raw`).
pub fn raw_sidecars(path: &Path) -> Vec<std::path::PathBuf> {
    raw::sidecar_paths(path)
}

/// True for a path named like a raw file (`.raw`, any case).
pub fn is_raw(path: &Path) -> bool {
    Format::of(path).is_some_and(|f| f.header.is_none())
}

impl Format {
    /// The format whose ending the path's file name has (any case).
    pub fn of(path: &Path) -> Option<Format> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let ends = |e: &&str| name.len() > e.len() && name.ends_with(*e);
        FORMATS
            .iter()
            .find(|f| f.extensions.iter().any(ends))
            .copied()
    }
}

// ---------------------------------------------------------------------------------------
// Shared helpers for the format modules.

/// Sample types any format can hold (wider than [`ScalarKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sample {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Sample {
    pub(crate) fn size(self) -> usize {
        match self {
            Sample::I8 | Sample::U8 => 1,
            Sample::I16 | Sample::U16 => 2,
            Sample::I32 | Sample::U32 | Sample::F32 => 4,
            Sample::F64 => 8,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Sample::I8 => "int8",
            Sample::U8 => "uint8",
            Sample::I16 => "int16",
            Sample::U16 => "uint16",
            Sample::I32 => "int32",
            Sample::U32 => "uint32",
            Sample::F32 => "float32",
            Sample::F64 => "float64",
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Sample::F32 | Sample::F64)
    }
}

/// Checks header dimensions (each in 1..=u32::MAX) and returns them as u32.
pub(crate) fn checked_dims(dims: [i64; 3]) -> Result<[u32; 3]> {
    let mut out = [0u32; 3];
    for (i, &d) in dims.iter().enumerate() {
        ensure!(
            d > 0,
            "non-positive dimension {d} along {} (dimensions {} x {} x {})",
            ["x", "y", "z"][i],
            dims[0],
            dims[1],
            dims[2]
        );
        out[i] = u32::try_from(d).map_err(|_| anyhow!("dimension {d} is too large"))?;
    }
    Ok(out)
}

/// Bytes of `dims` samples of `sample` as a header states them: overflow checked and,
/// when the options carry device limits, refused if the device cannot hold the volume
/// (each loader calls this before it reads or allocates the data).
pub(crate) fn header_bytes(dims: [u32; 3], sample: Sample, opts: &LoadOptions) -> Result<usize> {
    let bytes = data_bytes(dims, sample)?;
    if let Some(l) = opts.limits {
        // The texel the upload will use (see the module doc's value mapping): 8- and
        // 16-bit unsigned data stay normalised integers unless windowed; the rest is f32.
        let texel = match sample {
            Sample::U8 if opts.window.is_none() => 1,
            Sample::U16 if opts.window.is_none() => 2,
            _ => 4,
        };
        check_limits_texel(dims, texel, l.max_3d_extent, l.bytes_available)
            .map_err(|e| anyhow!("{e} (from the header; nothing was read)"))?;
    }
    Ok(bytes)
}

/// Bytes of `dims` samples of `sample`, with overflow checked.
pub(crate) fn data_bytes(dims: [u32; 3], sample: Sample) -> Result<usize> {
    dims.iter()
        .try_fold(sample.size() as u64, |acc, &d| acc.checked_mul(d as u64))
        .and_then(|b| usize::try_from(b).ok())
        .ok_or_else(|| {
            anyhow!(
                "{}x{}x{} {} voxels do not fit in memory (size overflows)",
                dims[0],
                dims[1],
                dims[2],
                sample.name()
            )
        })
}

/// Chooses the voxel spacing: the option, else the file's (checked), else 1.
pub(crate) fn resolve_spacing(opts: &LoadOptions, file: Option<[f64; 3]>) -> Result<[f32; 3]> {
    if let Some(s) = opts.spacing {
        return Ok(s);
    }
    match file {
        None => Ok([1.0; 3]),
        Some(s) => {
            let f = s.map(|x| x as f32);
            ensure!(
                f.iter().all(|x| x.is_finite() && *x > 0.0),
                "spacing {s:?} from the header is not finite and positive (give a spacing to \
                 override it)"
            );
            Ok(f)
        }
    }
}

/// Linear value rescaling `v * slope + inter` (NIfTI scl_*, DICOM Rescale*).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rescale {
    pub slope: f64,
    pub inter: f64,
}

impl Rescale {
    /// `None` when the rescale is the identity.
    pub(crate) fn non_identity(slope: f64, inter: f64) -> Option<Rescale> {
        (slope != 1.0 || inter != 0.0).then_some(Rescale { slope, inter })
    }
}

/// Builds the volume from exactly `dims × sample` bytes, following the value mapping of
/// the module doc.
pub(crate) fn build_volume(
    dims: [u32; 3],
    spacing: [f32; 3],
    sample: Sample,
    big_endian: bool,
    bytes: &[u8],
    rescale: Option<Rescale>,
    opts: &LoadOptions,
) -> Result<Volume> {
    let expected = data_bytes(dims, sample)?;
    ensure!(
        bytes.len() == expected,
        "internal: {} data bytes for {expected} expected",
        bytes.len()
    );
    let keep_unorm = rescale.is_none() && opts.window.is_none();
    let voxels = match sample {
        Sample::U8 if keep_unorm => Voxels::U8(bytes.to_vec()),
        Sample::U16 if keep_unorm => Voxels::U16(decode_u16(bytes, big_endian)),
        _ => {
            let mut v = decode_f32(sample, bytes, big_endian);
            if let Some(r) = rescale {
                for x in &mut v {
                    *x = (*x as f64 * r.slope + r.inter) as f32;
                }
            }
            Voxels::F32(v)
        }
    };
    let mut volume = loaded(dims, spacing, voxels, None, opts);
    volume.stored = Some(sample.name());
    Ok(volume)
}

/// A loaded volume: its voxels, the window the options ask for, the orientation read.
pub(crate) fn loaded(
    dims: [u32; 3],
    spacing: [f32; 3],
    voxels: Voxels,
    axes: Option<[[f32; 3]; 3]>,
    opts: &LoadOptions,
) -> Volume {
    Volume {
        dims,
        spacing,
        voxels,
        range: opts.window,
        axes,
        stored: None,
        spacing_stated: true,
        labels: false,
    }
}

pub(crate) fn decode_u16(bytes: &[u8], big_endian: bool) -> Vec<u16> {
    let f = if big_endian {
        u16::from_be_bytes
    } else {
        u16::from_le_bytes
    };
    bytes.chunks_exact(2).map(|c| f([c[0], c[1]])).collect()
}

/// Converts samples to f32 (exact for 8/16-bit integers, rounded for the others).
pub(crate) fn decode_f32(sample: Sample, bytes: &[u8], be: bool) -> Vec<f32> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {
            bytes
                .chunks_exact($n)
                .map(|c| {
                    let a: [u8; $n] = c.try_into().unwrap();
                    (if be {
                        <$t>::from_be_bytes(a)
                    } else {
                        <$t>::from_le_bytes(a)
                    }) as f32
                })
                .collect()
        };
    }
    match sample {
        Sample::U8 => bytes.iter().map(|&b| b as f32).collect(),
        Sample::I8 => bytes.iter().map(|&b| b as i8 as f32).collect(),
        Sample::U16 => conv!(u16, 2),
        Sample::I16 => conv!(i16, 2),
        Sample::U32 => conv!(u32, 4),
        Sample::I32 => conv!(i32, 4),
        Sample::F32 => conv!(f32, 4),
        Sample::F64 => conv!(f64, 8),
    }
}

/// Checks that `actual` bytes of data are what the header says. `what` names the data
/// ("data after the header", "data file 'x.raw'").
pub(crate) fn check_size(what: &str, actual: usize, expected: usize) -> Result<()> {
    ensure!(
        actual == expected,
        "{what} is {actual} bytes, header says {expected} bytes ({})",
        if actual < expected {
            "file too short: truncated?"
        } else {
            "file too long"
        }
    );
    Ok(())
}

/// Reads a decompressing stream that should yield exactly `expected` bytes. Reads at most
/// one byte more, so a header that claims a huge size allocates only what is there.
pub(crate) fn read_compressed<R: Read>(reader: R, kind: &str, expected: usize) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    reader
        .take(expected as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| anyhow!("{kind} data is corrupt or truncated: {e}"))?;
    ensure!(
        out.len() <= expected,
        "{kind} data decompresses to more than the {expected} bytes the header says"
    );
    ensure!(
        out.len() == expected,
        "{kind} data decompresses to {} bytes, header says {expected} bytes (truncated or \
         corrupt)",
        out.len()
    );
    Ok(out)
}

/// Decompresses a zlib stream, or a gzip stream when the data starts with the gzip magic.
pub(crate) fn inflate_zlib_or_gzip(data: &[u8], expected: usize) -> Result<Vec<u8>> {
    if data.starts_with(&[0x1f, 0x8b]) {
        read_compressed(flate2::read::MultiGzDecoder::new(data), "gzip", expected)
    } else {
        read_compressed(flate2::read::ZlibDecoder::new(data), "zlib", expected)
    }
}

/// Parses whitespace-separated ASCII numbers into `n` little-endian samples.
pub(crate) fn parse_ascii(text: &str, sample: Sample, n: usize) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(n.min(text.len() / 2 + 1) * sample.size());
    let mut count = 0usize;
    for tok in text.split(|c: char| c.is_whitespace() || c == ',') {
        if tok.is_empty() {
            continue;
        }
        ensure!(
            count < n,
            "ASCII data has more than the {n} values the header says"
        );
        let bad = || {
            anyhow!(
                "ASCII value #{count} '{tok}' is not a valid {}",
                sample.name()
            )
        };
        if sample.is_float() {
            let v: f64 = tok.parse().map_err(|_| bad())?;
            match sample {
                Sample::F32 => out.extend_from_slice(&(v as f32).to_le_bytes()),
                _ => out.extend_from_slice(&v.to_le_bytes()),
            }
        } else {
            let v: i64 = tok.parse().map_err(|_| bad())?;
            let ok = match sample {
                Sample::I8 => i8::try_from(v).map(|x| out.push(x as u8)).is_ok(),
                Sample::U8 => u8::try_from(v).map(|x| out.push(x)).is_ok(),
                Sample::I16 => i16::try_from(v)
                    .map(|x| out.extend_from_slice(&x.to_le_bytes()))
                    .is_ok(),
                Sample::U16 => u16::try_from(v)
                    .map(|x| out.extend_from_slice(&x.to_le_bytes()))
                    .is_ok(),
                Sample::I32 => i32::try_from(v)
                    .map(|x| out.extend_from_slice(&x.to_le_bytes()))
                    .is_ok(),
                _ => u32::try_from(v)
                    .map(|x| out.extend_from_slice(&x.to_le_bytes()))
                    .is_ok(),
            };
            ensure!(
                ok,
                "ASCII value #{count} '{tok}' is out of range for {}",
                sample.name()
            );
        }
        count += 1;
    }
    ensure!(
        count == n,
        "ASCII data has {count} values, header says {n} values"
    );
    Ok(out)
}

/// Parses a list of numbers separated by whitespace (and optionally commas).
pub(crate) fn parse_numbers<T: std::str::FromStr>(s: &str, what: &str) -> Result<Vec<T>> {
    s.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<T>()
                .map_err(|_| anyhow!("{what}: '{t}' is not a valid number"))
        })
        .collect()
}

/// Exactly three numbers.
pub(crate) fn parse3<T: std::str::FromStr + Copy>(s: &str, what: &str) -> Result<[T; 3]> {
    let v = parse_numbers::<T>(s, what)?;
    ensure!(
        v.len() == 3,
        "{what} has {} values, expected 3: '{s}'",
        v.len()
    );
    Ok([v[0], v[1], v[2]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checked_dims_rejects_non_positive_and_huge() {
        assert_eq!(checked_dims([2, 3, 4]).unwrap(), [2, 3, 4]);
        let e = checked_dims([2, 0, 4]).unwrap_err().to_string();
        assert!(e.contains("non-positive"), "{e}");
        let e = checked_dims([2, -5, 4]).unwrap_err().to_string();
        assert!(e.contains("non-positive"), "{e}");
        assert!(checked_dims([1 << 40, 1, 1]).is_err());
    }

    #[test]
    fn data_bytes_overflow_is_an_error() {
        assert_eq!(data_bytes([2, 3, 4], Sample::I16).unwrap(), 48);
        let e = data_bytes([u32::MAX; 3], Sample::F64)
            .unwrap_err()
            .to_string();
        assert!(e.contains("overflow"), "{e}");
    }

    #[test]
    fn check_limits_names_the_limit() {
        check_limits([256, 256, 256], 2048, Some(1 << 30)).unwrap();
        let e = check_limits([4096, 16, 16], 2048, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("maxImageDimension3D") && e.contains("2048"),
            "{e}"
        );
        let e = check_limits([1024, 1024, 1024], 2048, Some(1 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bytes available") && e.contains("4294967296"),
            "{e}"
        );
        let e = check_limits([0, 4, 4], 2048, None).unwrap_err().to_string();
        assert!(e.contains("zero"), "{e}");
        check_limits([u32::MAX; 3], u32::MAX, Some(u64::MAX)).unwrap_err();
        let v = Volume::new([1024, 1024, 1024], [1.0; 3], Voxels::U8(vec![])).ok();
        assert!(
            v.is_none(),
            "voxel count mismatch must be rejected by Volume::new"
        );
    }

    #[test]
    fn check_volume_limits_counts_the_real_texel_size() {
        let v = Volume::new([4, 4, 4], [1.0; 3], Voxels::U8(vec![0; 64])).unwrap();
        check_volume_limits(&v, 4, Some(64)).unwrap();
        assert!(check_limits([4, 4, 4], 4, Some(64)).is_err());
        assert!(check_volume_limits(&v, 3, None).is_err());
    }

    #[test]
    fn ascii_parsing_checks_counts_and_ranges() {
        assert_eq!(parse_ascii("1 2\n3", Sample::U8, 3).unwrap(), vec![1, 2, 3]);
        assert!(parse_ascii("1 2", Sample::U8, 3).is_err());
        assert!(parse_ascii("1 2 3 4", Sample::U8, 3).is_err());
        assert!(parse_ascii("1 256 3", Sample::U8, 3)
            .unwrap_err()
            .to_string()
            .contains("out of range"));
        assert_eq!(
            parse_ascii("-2 1.5", Sample::F32, 2).unwrap(),
            [(-2f32).to_le_bytes(), 1.5f32.to_le_bytes()].concat()
        );
    }

    #[test]
    fn value_mapping_follows_the_rule() {
        let opts = LoadOptions::default();
        let v = build_volume(
            [2, 1, 1],
            [1.0; 3],
            Sample::U16,
            true,
            &[1, 2, 0, 3],
            None,
            &opts,
        )
        .unwrap();
        assert_eq!(v.voxels, Voxels::U16(vec![0x0102, 3]));
        let v = build_volume(
            [2, 1, 1],
            [1.0; 3],
            Sample::I16,
            false,
            &[0xff, 0xff, 5, 0],
            None,
            &opts,
        )
        .unwrap();
        assert_eq!(v.voxels, Voxels::F32(vec![-1.0, 5.0]));
        assert_eq!(v.range, None);
        let windowed = LoadOptions {
            window: Some((0.0, 10.0)),
            ..Default::default()
        };
        let v = build_volume(
            [2, 1, 1],
            [1.0; 3],
            Sample::U8,
            false,
            &[7, 9],
            None,
            &windowed,
        )
        .unwrap();
        assert_eq!(v.voxels, Voxels::F32(vec![7.0, 9.0]));
        assert_eq!(v.range, Some((0.0, 10.0)));
        let r = Rescale::non_identity(2.0, -1024.0);
        let v = build_volume([2, 1, 1], [1.0; 3], Sample::U8, false, &[0, 10], r, &opts).unwrap();
        assert_eq!(v.voxels, Voxels::F32(vec![-1024.0, -1004.0]));
        assert!(Rescale::non_identity(1.0, 0.0).is_none());
    }

    #[test]
    fn format_detection_by_extension() {
        for (name, yes) in [
            ("a.raw", true),
            ("A.NRRD", true),
            ("a.nhdr", true),
            ("a.nii", true),
            ("a.nii.gz", true),
            ("a.mhd", true),
            ("a.mha", true),
            ("a.vti", true),
            ("scene.toml", false),
            ("a.gz", false),
            (".raw", false),
        ] {
            assert_eq!(is_volume_file(Path::new(name)), yes, "{name}");
        }
    }
}

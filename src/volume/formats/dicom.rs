//! DICOM series: a directory of single-frame image files, one slice each.
//!
//! A small DICOM reader of its own (no crate): Part-10 files (128-byte preamble + `DICM`,
//! or the meta group without preamble) and bare implicit-VR datasets; transfer syntaxes
//! Implicit VR Little Endian, Explicit VR Little Endian, Explicit VR Big Endian and
//! Deflated Explicit VR Little Endian. Compressed syntaxes (JPEG, JPEG-LS, JPEG 2000, RLE,
//! …) are refused with an error naming the syntax. Sequences of defined and undefined
//! length are skipped; every length is checked against the bytes present.
//!
//! The series: files without the DICOM marker or without pixel data (DICOMDIR, reports)
//! are passed over; the image files must all carry one SeriesInstanceUID (else an error
//! lists the series found). Slices are sorted by ImagePositionPatient projected on the
//! slice normal (the cross product of the ImageOrientationPatient row and column
//! directions), or by InstanceNumber when positions are missing. Spacing: PixelSpacing
//! (row spacing → y, column spacing → x) and the mean distance between slice positions
//! (without positions: SpacingBetweenSlices, else SliceThickness, else 1). Gaps that differ
//! from the median gap by more than 5 % are reported as missing slices. RescaleSlope /
//! RescaleIntercept are applied per slice. Samples: 1 per pixel (MONOCHROME1/2), 8, 16 or
//! 32 bits allocated, signed or unsigned; bits above BitsStored are masked off (and the
//! value sign-extended for signed data).

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, ensure, Context as _, Result};

use super::{resolve_spacing, LoadOptions};
use crate::volume::{Volume, Voxels};

type Tag = (u16, u16);

const TS_IMPLICIT_LE: &str = "1.2.840.10008.1.2";
const TS_EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const TS_DEFLATED_LE: &str = "1.2.840.10008.1.2.1.99";
const TS_EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";

const PIXEL_DATA: Tag = (0x7FE0, 0x0010);
const ITEM: Tag = (0xFFFE, 0xE000);
const ITEM_END: Tag = (0xFFFE, 0xE00D);
const SEQ_END: Tag = (0xFFFE, 0xE0DD);
const UNDEFINED: u32 = 0xFFFF_FFFF;
const MAX_DEPTH: usize = 32;

/// A directory holds a DICOM file when one of its first entries is named `.dcm` or has
/// the `DICM` marker.
pub(super) fn looks_like_series_dir(dir: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    entries.flatten().take(64).any(|e| {
        let p = e.path();
        p.is_file()
            && (p.extension().is_some_and(|x| x.eq_ignore_ascii_case("dcm")) || has_dicm_marker(&p))
    })
}

fn has_dicm_marker(p: &Path) -> bool {
    matches!(file_head(p), Some(h) if h.len() == 132 && &h[128..132] == b"DICM")
}

/// The first 132 bytes of a regular file (fewer if it is shorter): enough to tell a
/// DICOM file ([`dicom_start`]) without reading the rest.
fn file_head(p: &Path) -> Option<Vec<u8>> {
    use std::io::Read;
    let f = std::fs::File::open(p).ok()?;
    if !f.metadata().ok()?.is_file() {
        return None;
    }
    let mut head = Vec::with_capacity(132);
    f.take(132).read_to_end(&mut head).ok()?;
    Some(head)
}

/// Where a DICOM file's meta group or dataset starts and whether it has a meta group, from
/// its first 132 bytes; `None` when it is not DICOM.
fn dicom_start(bytes: &[u8]) -> Option<(usize, bool)> {
    if bytes.len() >= 132 && &bytes[128..132] == b"DICM" {
        Some((132, true)) // Part 10 file: preamble + DICM + meta group
    } else if bytes.len() >= 8
        && bytes[0..2] == [2, 0]
        && bytes[4..6].iter().all(u8::is_ascii_uppercase)
    {
        Some((0, true)) // meta group without preamble
    } else if bytes.len() >= 8 && bytes[0..2] == [8, 0] {
        Some((0, false)) // bare dataset, implicit VR little endian
    } else {
        None
    }
}

/// One image file's attributes.
#[derive(Debug, Default)]
struct Slice {
    file: PathBuf,
    series: String,
    rows: u16,
    cols: u16,
    samples: u16,
    bits_alloc: u16,
    bits_stored: u16,
    high_bit: u16,
    signed: bool,
    photometric: String,
    frames: i64,
    position: Option<[f64; 3]>,
    orientation: Option<[f64; 6]>,
    instance: Option<i64>,
    pixel_spacing: Option<[f64; 2]>,
    thickness: Option<f64>,
    between: Option<f64>,
    slope: f64,
    intercept: f64,
    big_endian: bool,
    pixels: Vec<u8>,
}

pub(super) fn load_series(dir: &Path, opts: &LoadOptions) -> Result<Volume> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| anyhow!("cannot read directory: {e}"))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    let mut slices = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap_or_default().to_string_lossy();
        // Look at the head first: a folder of other files costs 132 bytes a file.
        if !file_head(f).is_some_and(|h| dicom_start(&h).is_some()) {
            continue;
        }
        let bytes = std::fs::read(f).map_err(|e| anyhow!("cannot read '{name}': {e}"))?;
        if let Some(s) = parse_file(f, &bytes).with_context(|| format!("'{name}'"))? {
            slices.push(s);
        }
    }
    ensure!(
        !slices.is_empty(),
        "no DICOM image files found ({} files looked at)",
        files.len()
    );

    // One series only.
    let mut series: Vec<(String, usize)> = Vec::new();
    for s in &slices {
        match series.iter_mut().find(|(uid, _)| *uid == s.series) {
            Some((_, n)) => *n += 1,
            None => series.push((s.series.clone(), 1)),
        }
    }
    if series.len() > 1 {
        let list: Vec<String> = series
            .iter()
            .map(|(uid, n)| {
                let uid = if uid.is_empty() {
                    "(no SeriesInstanceUID)"
                } else {
                    uid
                };
                format!("{uid} ({n} files)")
            })
            .collect();
        bail!(
            "mixed DICOM series: {} series in one directory: {}; put one series per directory",
            series.len(),
            list.join(", ")
        );
    }

    // Every slice must have the first one's geometry and sample layout.
    let first = &slices[0];
    for s in &slices {
        let name = file_name(&s.file);
        ensure!(
            (s.rows, s.cols) == (first.rows, first.cols),
            "'{name}' is {}x{} pixels, '{}' is {}x{}",
            s.cols,
            s.rows,
            file_name(&first.file),
            first.cols,
            first.rows
        );
        ensure!(
            (s.bits_alloc, s.bits_stored, s.high_bit, s.signed)
                == (
                    first.bits_alloc,
                    first.bits_stored,
                    first.high_bit,
                    first.signed
                ),
            "'{name}' has a different pixel format (bits allocated/stored, sign) than '{}'",
            file_name(&first.file)
        );
    }

    let n = slices.len();
    let all_positioned = slices
        .iter()
        .all(|s| s.position.is_some() && s.orientation.is_some());
    let dz;
    // The voxel axes in the patient's LPS frame: rows (x), columns (y), and the slice
    // normal (z, the order the slices are sorted in below).
    let mut axes = None;
    if all_positioned {
        let first = &slices[0];
        let o = first.orientation.unwrap();
        for s in &slices {
            let so = s.orientation.unwrap();
            ensure!(
                o.iter().zip(&so).all(|(a, b)| (a - b).abs() < 1e-3),
                "'{}' has ImageOrientationPatient {so:?}, '{}' has {o:?} (not one stack of \
                 parallel slices)",
                file_name(&s.file),
                file_name(&first.file)
            );
        }
        let normal = cross([o[0], o[1], o[2]], [o[3], o[4], o[5]]);
        let len = dot(normal, normal).sqrt();
        ensure!(
            len > 0.5,
            "ImageOrientationPatient {o:?} does not give a slice normal"
        );
        let unit = |v: [f64; 3]| {
            let l = dot(v, v).sqrt().max(1e-12);
            v.map(|c| (c / l) as f32)
        };
        axes = Some([
            unit([o[0], o[1], o[2]]),
            unit([o[3], o[4], o[5]]),
            unit(normal),
        ]);
        let d = |s: &Slice| dot(s.position.unwrap(), normal) / len;
        slices.sort_by(|a, b| d(a).total_cmp(&d(b)));
        let pos: Vec<f64> = slices.iter().map(d).collect();
        if n >= 2 {
            let gaps: Vec<f64> = pos.windows(2).map(|w| w[1] - w[0]).collect();
            for (i, g) in gaps.iter().enumerate() {
                ensure!(
                    *g > 1e-4,
                    "'{}' and '{}' are at the same slice position {:.4} (duplicate slices?)",
                    file_name(&slices[i].file),
                    file_name(&slices[i + 1].file),
                    pos[i]
                );
            }
            let mut sorted = gaps.clone();
            sorted.sort_by(f64::total_cmp);
            let median = sorted[sorted.len() / 2];
            for (i, &g) in gaps.iter().enumerate() {
                ensure!(
                    (g - median).abs() <= 0.05 * median,
                    "missing slices? gap of {g:.4} between slice positions {:.4} ('{}') and \
                     {:.4} ('{}'); the usual gap is {median:.4}",
                    pos[i],
                    file_name(&slices[i].file),
                    pos[i + 1],
                    file_name(&slices[i + 1].file)
                );
            }
            dz = (pos[n - 1] - pos[0]) / (n - 1) as f64;
        } else {
            dz = fallback_dz(&slices[0]);
        }
    } else {
        for s in &slices {
            ensure!(
                s.instance.is_some(),
                "cannot order the slices: '{}' has neither ImagePositionPatient + \
                 ImageOrientationPatient nor InstanceNumber",
                file_name(&s.file)
            );
        }
        slices.sort_by_key(|s| s.instance.unwrap());
        for w in slices.windows(2) {
            ensure!(
                w[0].instance != w[1].instance,
                "'{}' and '{}' have the same InstanceNumber {} (duplicate slices?)",
                file_name(&w[0].file),
                file_name(&w[1].file),
                w[0].instance.unwrap()
            );
        }
        dz = fallback_dz(&slices[0]);
    }

    let first = &slices[0];
    let ps = first.pixel_spacing.unwrap_or([1.0, 1.0]);
    let spacing = resolve_spacing(opts, Some([ps[1], ps[0], dz]))?;
    let dims = [first.cols as u32, first.rows as u32, n as u32];
    let per_slice = first.cols as usize * first.rows as usize;

    let rescaled = slices.iter().any(|s| s.slope != 1.0 || s.intercept != 0.0);
    let keep_unorm = !rescaled && opts.window.is_none() && !first.signed;
    if let Some(l) = opts.limits {
        // What the device cannot hold is refused before the volume is assembled, with the
        // texel size the upload will use (as the other loaders do from their headers).
        let texel = match first.bits_alloc {
            8 if keep_unorm => 1,
            16 if keep_unorm => 2,
            _ => 4,
        };
        super::check_limits_texel(dims, texel, l.max_3d_extent, l.bytes_available)
            .map_err(|e| anyhow!("{e} (from the headers; no volume was assembled)"))?;
    }
    let voxels = match first.bits_alloc {
        8 if keep_unorm => {
            let mut v = Vec::with_capacity(per_slice * n);
            for s in &slices {
                v.extend(
                    s.pixels[..per_slice]
                        .iter()
                        .map(|&x| mask(s, x as u32) as u8),
                );
            }
            Voxels::U8(v)
        }
        16 if keep_unorm => {
            let mut v = Vec::with_capacity(per_slice * n);
            for s in &slices {
                v.extend(raw_u32(s, per_slice).map(|x| mask(s, x) as u16));
            }
            Voxels::U16(v)
        }
        _ => {
            let mut v = Vec::with_capacity(per_slice * n);
            for s in &slices {
                v.extend(
                    raw_u32(s, per_slice)
                        .map(|x| (value(s, mask(s, x)) * s.slope + s.intercept) as f32),
                );
            }
            Voxels::F32(v)
        }
    };
    let mut volume = super::loaded(dims, spacing, voxels, axes, opts);
    volume.stored = Some(match (first.bits_alloc, first.signed) {
        (8, false) => "uint8",
        (8, true) => "int8",
        (16, false) => "uint16",
        (16, true) => "int16",
        (_, false) => "uint32",
        (_, true) => "int32",
    });
    Ok(volume)
}

fn fallback_dz(s: &Slice) -> f64 {
    s.between
        .or(s.thickness)
        .filter(|v| *v > 0.0)
        .unwrap_or(1.0)
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The stored samples of one slice as unsigned words (8, 16 or 32 bits).
fn raw_u32(s: &Slice, n: usize) -> Box<dyn Iterator<Item = u32> + '_> {
    let be = s.big_endian;
    match s.bits_alloc {
        8 => Box::new(s.pixels[..n].iter().map(|&b| b as u32)),
        16 => Box::new(s.pixels[..2 * n].chunks_exact(2).map(move |c| {
            let a = [c[0], c[1]];
            (if be {
                u16::from_be_bytes(a)
            } else {
                u16::from_le_bytes(a)
            }) as u32
        })),
        _ => Box::new(s.pixels[..4 * n].chunks_exact(4).map(move |c| {
            let a = [c[0], c[1], c[2], c[3]];
            if be {
                u32::from_be_bytes(a)
            } else {
                u32::from_le_bytes(a)
            }
        })),
    }
}

/// Keeps the BitsStored bits that end at HighBit.
fn mask(s: &Slice, x: u32) -> u32 {
    let shift = (s.high_bit + 1 - s.bits_stored) as u32;
    let bits = s.bits_stored as u32;
    let m = if bits >= 32 {
        u32::MAX
    } else {
        (1u32 << bits) - 1
    };
    (x >> shift) & m
}

/// The masked stored value as a number (sign-extended for signed data).
fn value(s: &Slice, x: u32) -> f64 {
    let bits = s.bits_stored as u32;
    if s.signed && bits < 32 && x & (1 << (bits - 1)) != 0 {
        x as f64 - (1u64 << bits) as f64
    } else if s.signed && bits == 32 {
        x as i32 as f64
    } else {
        x as f64
    }
}

// ---------------------------------------------------------------------------------------
// Parsing one file.

/// A cursor over a dataset in one transfer syntax.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    explicit: bool,
    big_endian: bool,
}

impl<'a> Reader<'a> {
    fn u16(&mut self) -> Result<u16> {
        let b = self.take(2)?;
        Ok(if self.big_endian {
            u16::from_be_bytes([b[0], b[1]])
        } else {
            u16::from_le_bytes([b[0], b[1]])
        })
    }

    fn u32(&mut self) -> Result<u32> {
        let b = self.take(4)?;
        let a = [b[0], b[1], b[2], b[3]];
        Ok(if self.big_endian {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        })
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        let end = end.ok_or_else(|| {
            anyhow!(
                "file ends at byte {} inside an element needing {n} bytes at {} (truncated?)",
                self.buf.len(),
                self.pos
            )
        })?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn at_end(&self) -> bool {
        self.pos >= self.buf.len()
    }

    /// Reads an element header: tag, VR (explicit syntaxes), value length.
    fn header(&mut self) -> Result<(Tag, [u8; 2], u32)> {
        let tag = (self.u16()?, self.u16()?);
        if tag.0 == 0xFFFE {
            return Ok((tag, *b"  ", self.u32()?));
        }
        if !self.explicit {
            return Ok((tag, *b"  ", self.u32()?));
        }
        let vr = self.take(2)?;
        let vr = [vr[0], vr[1]];
        ensure!(
            vr.iter().all(|c| c.is_ascii_uppercase()),
            "bad value representation {:?} for element ({:04X},{:04X}) at byte {} (wrong \
             transfer syntax?)",
            String::from_utf8_lossy(&vr),
            tag.0,
            tag.1,
            self.pos - 2
        );
        let long = matches!(
            &vr,
            b"OB"
                | b"OD"
                | b"OF"
                | b"OL"
                | b"OV"
                | b"OW"
                | b"SQ"
                | b"UC"
                | b"UN"
                | b"UR"
                | b"UT"
                | b"SV"
                | b"UV"
        );
        let len = if long {
            self.take(2)?;
            self.u32()?
        } else {
            self.u16()? as u32
        };
        Ok((tag, vr, len))
    }

    /// Skips the items of a sequence of undefined length, up to its delimiter.
    fn skip_sequence(&mut self, depth: usize) -> Result<()> {
        ensure!(depth < MAX_DEPTH, "sequences nested too deeply");
        loop {
            let (tag, _, len) = self.header()?;
            match tag {
                SEQ_END => return Ok(()),
                ITEM if len == UNDEFINED => self.skip_item(depth + 1)?,
                ITEM => {
                    self.take(len as usize)?;
                }
                _ => bail!(
                    "unexpected element ({:04X},{:04X}) inside a sequence at byte {}",
                    tag.0,
                    tag.1,
                    self.pos
                ),
            }
        }
    }

    /// Skips the elements of an item of undefined length, up to its delimiter.
    fn skip_item(&mut self, depth: usize) -> Result<()> {
        ensure!(depth < MAX_DEPTH, "sequences nested too deeply");
        loop {
            let (tag, _, len) = self.header()?;
            if tag == ITEM_END {
                return Ok(());
            }
            if len == UNDEFINED {
                ensure!(
                    tag != PIXEL_DATA,
                    "encapsulated pixel data inside a sequence is not supported"
                );
                self.skip_sequence(depth + 1)?;
            } else {
                self.take(len as usize)?;
            }
        }
    }
}

fn ts_name(uid: &str) -> &'static str {
    match uid {
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended",
        "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => "JPEG Lossless",
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => "JPEG-LS",
        "1.2.840.10008.1.2.4.90" | "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.201" | "1.2.840.10008.1.2.4.202" | "1.2.840.10008.1.2.4.203" => {
            "HTJ2K"
        }
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        "1.2.840.10008.1.2.4.100"
        | "1.2.840.10008.1.2.4.101"
        | "1.2.840.10008.1.2.4.102"
        | "1.2.840.10008.1.2.4.103" => "MPEG video",
        _ => "unknown",
    }
}

fn text(v: &[u8]) -> String {
    String::from_utf8_lossy(v)
        .trim_matches(|c: char| c == '\0' || c.is_whitespace())
        .to_string()
}

fn numbers(v: &[u8], what: &str) -> Result<Vec<f64>> {
    text(v)
        .split('\\')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("{what} value '{t}' is not a number"))
        })
        .collect()
}

fn number(v: &[u8], what: &str) -> Result<f64> {
    numbers(v, what)?
        .first()
        .copied()
        .ok_or_else(|| anyhow!("{what} is empty"))
}

/// Parses one file; `None` for files that are not DICOM images (no marker and no plausible
/// dataset, or no pixel data).
fn parse_file(path: &Path, bytes: &[u8]) -> Result<Option<Slice>> {
    // The meta group is explicit VR little endian.
    let Some((meta_at, has_meta)) = dicom_start(bytes) else {
        return Ok(None);
    };
    let mut ts = TS_IMPLICIT_LE.to_string();
    let mut data_at = meta_at;
    if has_meta {
        let mut r = Reader {
            buf: bytes,
            pos: meta_at,
            explicit: true,
            big_endian: false,
        };
        while r.pos + 2 <= bytes.len() && bytes[r.pos..r.pos + 2] == [2, 0] {
            let (tag, _, len) = r.header()?;
            ensure!(len != UNDEFINED, "undefined length in the file meta group");
            let v = r.take(len as usize)?;
            if tag == (0x0002, 0x0010) {
                ts = text(v);
            }
        }
        data_at = r.pos;
    }
    let (explicit, big_endian, inflated);
    match ts.as_str() {
        TS_IMPLICIT_LE => (explicit, big_endian, inflated) = (false, false, None),
        TS_EXPLICIT_LE => (explicit, big_endian, inflated) = (true, false, None),
        TS_EXPLICIT_BE => (explicit, big_endian, inflated) = (true, true, None),
        TS_DEFLATED_LE => {
            use std::io::Read;
            let mut out = Vec::new();
            flate2::read::DeflateDecoder::new(&bytes[data_at..])
                .read_to_end(&mut out)
                .map_err(|e| anyhow!("deflated dataset is corrupt: {e}"))?;
            (explicit, big_endian, inflated) = (true, false, Some(out));
        }
        other => bail!(
            "transfer syntax {other} ({}) is not supported: only uncompressed syntaxes \
             (implicit/explicit VR little endian, explicit VR big endian, deflated)",
            ts_name(other)
        ),
    }
    let buf: &[u8] = match &inflated {
        Some(v) => v,
        None => &bytes[data_at..],
    };
    let mut r = Reader {
        buf,
        pos: 0,
        explicit,
        big_endian,
    };
    let mut s = Slice {
        file: path.to_path_buf(),
        samples: 1,
        frames: 1,
        slope: 1.0,
        intercept: 0.0,
        big_endian,
        ..Default::default()
    };
    let mut have = [false; 4]; // rows, cols, bits allocated, pixel data
    let us = |r: &Reader, v: &[u8], what: &str| -> Result<u16> {
        ensure!(v.len() >= 2, "{what} has {} bytes, expected 2", v.len());
        Ok(if r.big_endian {
            u16::from_be_bytes([v[0], v[1]])
        } else {
            u16::from_le_bytes([v[0], v[1]])
        })
    };
    while !r.at_end() {
        let (tag, vr, len) = r.header()?;
        if len == UNDEFINED {
            if tag == PIXEL_DATA {
                bail!("encapsulated (compressed) pixel data is not supported");
            }
            ensure!(
                !explicit || matches!(&vr, b"SQ" | b"UN" | b"OB" | b"OW"),
                "undefined length for a non-sequence element ({:04X},{:04X})",
                tag.0,
                tag.1
            );
            r.skip_sequence(0)?;
            continue;
        }
        ensure!(
            tag.0 != 0xFFFE,
            "unexpected item tag ({:04X},{:04X}) at the top level",
            tag.0,
            tag.1
        );
        let v = r
            .take(len as usize)
            .with_context(|| format!("element ({:04X},{:04X}) of {len} bytes", tag.0, tag.1))?;
        match tag {
            (0x0020, 0x000E) => s.series = text(v),
            (0x0020, 0x0013) => {
                s.instance = text(v).parse::<f64>().ok().map(|x| x as i64);
            }
            (0x0020, 0x0032) => {
                let p = numbers(v, "ImagePositionPatient")?;
                ensure!(p.len() == 3, "ImagePositionPatient has {} values", p.len());
                s.position = Some([p[0], p[1], p[2]]);
            }
            (0x0020, 0x0037) => {
                let o = numbers(v, "ImageOrientationPatient")?;
                ensure!(
                    o.len() == 6,
                    "ImageOrientationPatient has {} values",
                    o.len()
                );
                s.orientation = Some([o[0], o[1], o[2], o[3], o[4], o[5]]);
            }
            (0x0028, 0x0030) => {
                let p = numbers(v, "PixelSpacing")?;
                ensure!(p.len() == 2, "PixelSpacing has {} values", p.len());
                s.pixel_spacing = Some([p[0], p[1]]);
            }
            (0x0018, 0x0050) => s.thickness = number(v, "SliceThickness").ok(),
            (0x0018, 0x0088) => s.between = number(v, "SpacingBetweenSlices").ok(),
            (0x0028, 0x0002) => s.samples = us(&r, v, "SamplesPerPixel")?,
            (0x0028, 0x0004) => s.photometric = text(v),
            (0x0028, 0x0008) => {
                s.frames = text(v)
                    .parse()
                    .map_err(|_| anyhow!("bad NumberOfFrames '{}'", text(v)))?
            }
            (0x0028, 0x0010) => {
                s.rows = us(&r, v, "Rows")?;
                have[0] = true;
            }
            (0x0028, 0x0011) => {
                s.cols = us(&r, v, "Columns")?;
                have[1] = true;
            }
            (0x0028, 0x0100) => {
                s.bits_alloc = us(&r, v, "BitsAllocated")?;
                have[2] = true;
            }
            (0x0028, 0x0101) => s.bits_stored = us(&r, v, "BitsStored")?,
            (0x0028, 0x0102) => s.high_bit = us(&r, v, "HighBit")?,
            (0x0028, 0x0103) => s.signed = us(&r, v, "PixelRepresentation")? != 0,
            (0x0028, 0x1052) => s.intercept = number(v, "RescaleIntercept")?,
            (0x0028, 0x1053) => s.slope = number(v, "RescaleSlope")?,
            PIXEL_DATA => {
                s.pixels = v.to_vec();
                have[3] = true;
                break;
            }
            _ => {}
        }
    }
    if !have[3] {
        return Ok(None); // not an image (DICOMDIR, report, …)
    }
    ensure!(
        have[0] && have[1] && have[2],
        "image without Rows, Columns or BitsAllocated"
    );
    ensure!(
        s.samples == 1,
        "{} samples per pixel ({}) are not supported (only grey-scale)",
        s.samples,
        s.photometric
    );
    ensure!(
        s.frames == 1,
        "multi-frame images ({} frames) are not supported (one slice per file)",
        s.frames
    );
    ensure!(
        matches!(s.bits_alloc, 8 | 16 | 32),
        "BitsAllocated {} is not supported (8, 16 or 32)",
        s.bits_alloc
    );
    ensure!(
        s.rows > 0 && s.cols > 0,
        "non-positive dimension: {}x{} pixels",
        s.cols,
        s.rows
    );
    if s.bits_stored == 0 {
        s.bits_stored = s.bits_alloc;
    }
    if s.high_bit == 0 && s.bits_stored > 1 {
        s.high_bit = s.bits_stored - 1;
    }
    ensure!(
        s.bits_stored <= s.bits_alloc
            && s.high_bit < s.bits_alloc
            && s.high_bit + 1 >= s.bits_stored,
        "inconsistent BitsAllocated {} / BitsStored {} / HighBit {}",
        s.bits_alloc,
        s.bits_stored,
        s.high_bit
    );
    ensure!(
        s.slope.is_finite() && s.intercept.is_finite(),
        "RescaleSlope/RescaleIntercept not finite"
    );
    let expected = s.rows as usize * s.cols as usize * (s.bits_alloc as usize / 8);
    // Values are padded to an even length: one extra byte is allowed.
    ensure!(
        s.pixels.len() == expected || s.pixels.len() == expected + 1,
        "pixel data is {} bytes, header says {}x{} pixels of {} bits = {expected} bytes",
        s.pixels.len(),
        s.cols,
        s.rows,
        s.bits_alloc
    );
    Ok(Some(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masking_and_sign_extension() {
        let s = Slice {
            bits_alloc: 16,
            bits_stored: 12,
            high_bit: 11,
            signed: true,
            ..Default::default()
        };
        assert_eq!(value(&s, mask(&s, 0xF800)), -2048.0);
        assert_eq!(value(&s, mask(&s, 0x07FF)), 2047.0);
        assert_eq!(value(&s, mask(&s, 0xFFFF)), -1.0);
        let u = Slice { signed: false, ..s };
        assert_eq!(value(&u, mask(&u, 0xF123)), 0x123 as f64);
    }

    #[test]
    fn transfer_syntax_names() {
        assert_eq!(ts_name("1.2.840.10008.1.2.4.70"), "JPEG Lossless");
        assert_eq!(ts_name("1.2.3"), "unknown");
    }
}

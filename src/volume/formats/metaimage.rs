//! MetaImage (ITK MetaIO): `.mhd` with a separate data file and `.mha` with the data
//! after the header (`ElementDataFile = LOCAL`).
//!
//! Supported: `NDims = 3`, one channel, `ElementType` MET_CHAR, MET_UCHAR, MET_SHORT,
//! MET_USHORT, MET_INT, MET_UINT, MET_FLOAT, MET_DOUBLE; `CompressedData = True` (zlib, or
//! gzip when the data starts with the gzip magic); `ElementSpacing` (else `ElementSize`);
//! `BinaryDataByteOrderMSB` / `ElementByteOrderMSB`; `HeaderSize` (bytes to skip in the
//! data file, -1: data at its end); `BinaryData = False` (ASCII numbers); orientation
//! from `TransformMatrix` (or `AnatomicalOrientation`), in ITK's LPS frame.
//! Not supported (clear error): `ElementDataFile = LIST` and file patterns, several
//! channels, other element types, NDims other than 3.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{anyhow, bail, ensure, Context as _, Result};

use super::{
    build_volume, check_size, checked_dims, header_bytes, inflate_zlib_or_gzip, parse3,
    parse_ascii, parse_numbers, read_file, read_promised, resolve_spacing, LoadOptions, Sample,
};
use crate::volume::orientation::{parse_itk_code, unit_axes};
use crate::volume::Volume;

pub(super) fn load(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    let file = read_file(path)?;
    // Header lines "Key = Value" up to and including ElementDataFile, which is last.
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut pos = 0;
    let mut data_start = None;
    while pos < file.len() {
        let end = file[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(file.len(), |i| pos + i + 1);
        let line = String::from_utf8_lossy(&file[pos..end]);
        let line = line.trim();
        pos = end;
        if line.is_empty() {
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            bail!(
                "malformed header line '{}' (expected 'Key = Value'; not a MetaImage file?)",
                line.chars().take(60).collect::<String>()
            );
        };
        let key = k.trim().to_ascii_lowercase();
        let done = key == "elementdatafile";
        ensure!(
            fields.insert(key.clone(), v.trim().to_string()).is_none(),
            "'{}' is given twice (which one is meant?)",
            k.trim()
        );
        if done {
            data_start = Some(pos);
            break;
        }
    }
    // ElementDataFile ends the header: with the data in another file, any line after it
    // would be ignored (an ElementSpacing there was), so it is an error.
    if let (Some(start), Some(f)) = (data_start, fields.get("elementdatafile")) {
        // (LIST and file patterns, whose names follow, are refused below.)
        let external = !f.eq_ignore_ascii_case("local")
            && !f.to_ascii_uppercase().starts_with("LIST")
            && !f.contains('%');
        let rest = String::from_utf8_lossy(&file[start..]);
        if external && !rest.trim().is_empty() {
            bail!(
                "header lines after ElementDataFile ('{}') would be ignored: ElementDataFile \
                 must be the last line",
                rest.trim()
                    .lines()
                    .next()
                    .unwrap_or("")
                    .chars()
                    .take(60)
                    .collect::<String>()
            );
        }
    }
    let data_start =
        data_start.ok_or_else(|| anyhow!("header has no ElementDataFile line (truncated?)"))?;
    let get = |k: &str| fields.get(k).map(String::as_str);
    let truthy = |k: &str| get(k).is_some_and(|v| v.eq_ignore_ascii_case("true"));

    let ndims = get("ndims").unwrap_or("3");
    ensure!(
        ndims == "3",
        "NDims = {ndims} is not supported (only 3-D volumes)"
    );
    let dim_size = get("dimsize").ok_or_else(|| anyhow!("header has no DimSize"))?;
    let dims = checked_dims(parse3::<i64>(dim_size, "DimSize")?)?;
    if let Some(c) = get("elementnumberofchannels") {
        ensure!(
            c == "1",
            "ElementNumberOfChannels = {c} is not supported (only scalar volumes)"
        );
    }
    let et = get("elementtype").ok_or_else(|| anyhow!("header has no ElementType"))?;
    let sample = match et.to_ascii_uppercase().as_str() {
        "MET_CHAR" => Sample::I8,
        "MET_UCHAR" => Sample::U8,
        "MET_SHORT" => Sample::I16,
        "MET_USHORT" => Sample::U16,
        "MET_INT" => Sample::I32,
        "MET_UINT" => Sample::U32,
        "MET_FLOAT" => Sample::F32,
        "MET_DOUBLE" => Sample::F64,
        _ => bail!(
            "unsupported ElementType '{et}' (supported: MET_CHAR, MET_UCHAR, MET_SHORT, \
             MET_USHORT, MET_INT, MET_UINT, MET_FLOAT, MET_DOUBLE)"
        ),
    };
    let expected = header_bytes(dims, sample, opts)?;
    let big_endian = truthy("binarydatabyteordermsb") || truthy("elementbyteordermsb");
    let compressed = truthy("compresseddata");
    let binary = get("binarydata").map_or(true, |v| v.eq_ignore_ascii_case("true"));
    let spacing = match get("elementspacing").or(get("elementsize")) {
        Some(s) => Some(parse3::<f64>(s, "ElementSpacing")?),
        None => None,
    };
    let header_size: i64 = match get("headersize") {
        Some(s) => s.parse().map_err(|_| anyhow!("bad HeaderSize '{s}'"))?,
        None => 0,
    };
    ensure!(header_size >= -1, "bad HeaderSize {header_size}");

    let edf = get("elementdatafile").unwrap_or_default();
    let detached;
    let (data, what): (&[u8], String) = if edf.eq_ignore_ascii_case("local") {
        (&file[data_start..], "data after the header".to_string())
    } else {
        ensure!(
            !edf.is_empty() && !edf.to_ascii_uppercase().starts_with("LIST") && !edf.contains('%'),
            "ElementDataFile = '{edf}' is not supported (LOCAL or one file name)"
        );
        let dir = path.parent().unwrap_or(Path::new("."));
        // Uncompressed binary data at a known offset: read no more than promised.
        detached = if binary && !compressed && header_size >= 0 {
            let promised = (header_size as u64).saturating_add(expected as u64);
            read_promised(&dir.join(edf), &format!("data file '{edf}'"), promised)?
        } else {
            read_file(&dir.join(edf))?
        };
        (&detached, format!("data file '{edf}'"))
    };

    let bytes: Vec<u8>;
    let payload: &[u8] = if compressed {
        ensure!(
            header_size >= 0,
            "HeaderSize = -1 is not allowed with compressed data"
        );
        let skip = header_size as usize;
        ensure!(
            skip <= data.len(),
            "{what} is shorter than HeaderSize {skip}"
        );
        let data = &data[skip..];
        let stated = match get("compresseddatasize") {
            Some(cs) => Some(
                cs.parse::<u64>()
                    .map_err(|_| anyhow!("bad CompressedDataSize '{cs}'"))?,
            ),
            None => None,
        };
        bytes = match stated {
            Some(cs) if data.len() as u64 != cs => {
                // A stale CompressedDataSize: VTK's own frog (frogtissue.mhd, the
                // pyvista and VTK example data) says 260020 bytes of a 262087-byte
                // stream. What the header must get right, the voxels, decides: a stream
                // that inflates to exactly the dimensions' bytes is used, and said so.
                let inflated = inflate_zlib_or_gzip(data, expected).with_context(|| {
                    format!(
                        "{what} is {} bytes, header says CompressedDataSize = {cs} bytes",
                        data.len()
                    )
                })?;
                log::warn!(
                    "{}: {what} is {} bytes where the header says CompressedDataSize = {cs}; \
                     the compressed data in it inflate to the {expected} bytes the header's \
                     DimSize and ElementType need, so they are used",
                    path.display(),
                    data.len()
                );
                inflated
            }
            _ => inflate_zlib_or_gzip(data, expected).with_context(|| what.clone())?,
        };
        &bytes
    } else if binary {
        let start = if header_size == -1 {
            ensure!(
                data.len() >= expected,
                "{what} is {} bytes, header says {expected} bytes (file too short: truncated?)",
                data.len()
            );
            data.len() - expected
        } else {
            let skip = header_size as usize;
            ensure!(
                skip <= data.len(),
                "{what} is {} bytes, shorter than HeaderSize {skip}",
                data.len()
            );
            skip
        };
        check_size(&what, data.len() - start, expected)?;
        &data[start..]
    } else {
        let text = String::from_utf8_lossy(data);
        bytes =
            parse_ascii(&text, sample, expected / sample.size()).with_context(|| what.clone())?;
        &bytes
    };
    let big_endian = big_endian && (binary || compressed);
    let stated = spacing.is_some() || opts.spacing.is_some();
    let spacing = resolve_spacing(opts, spacing)?;
    let mut volume = build_volume(dims, spacing, sample, big_endian, payload, None, opts)?;
    volume.spacing_stated = stated;
    volume.axes = header_axes(&fields)?;
    Ok(volume)
}

/// The voxel axes in LPS: ITK's physical space is LPS and `TransformMatrix` (synonyms
/// `Rotation`, `Orientation`) holds the direction of voxel axis i in its numbers 3i..3i+3
/// (ITK's MetaImageIO reads it so); without one, `AnatomicalOrientation` in ITK's "from"
/// convention (`orientation` module: RAI is LPS). `None` when neither is there; a
/// malformed one is an error.
fn header_axes(fields: &HashMap<String, String>) -> Result<Option<[[f32; 3]; 3]>> {
    let get = |k: &str| fields.get(k).map(String::as_str);
    let matrix = ["transformmatrix", "rotation", "orientation"]
        .iter()
        .find_map(|k| get(k));
    if let Some(m) = matrix {
        let v = parse_numbers::<f64>(m, "TransformMatrix")?;
        ensure!(
            v.len() == 9,
            "TransformMatrix has {} numbers, a 3-D image needs 9",
            v.len()
        );
        let dirs = std::array::from_fn(|i| std::array::from_fn(|j| v[3 * i + j]));
        let axes = unit_axes(dirs)
            .ok_or_else(|| anyhow!("TransformMatrix '{m}' is degenerate (no orientation)"))?;
        return Ok(Some(axes));
    }
    match get("anatomicalorientation") {
        // "???" is what MetaIO writes when it does not know.
        Some(code) if !code.contains('?') => parse_itk_code(code)
            .map(Some)
            .with_context(|| format!("AnatomicalOrientation '{code}'")),
        _ => Ok(None),
    }
}

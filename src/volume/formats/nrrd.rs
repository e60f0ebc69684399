//! NRRD (teem's "nearly raw raster data"): attached `.nrrd` and detached `.nhdr` headers.
//!
//! Supported: 3-D scalar data; types (u)char, (u)short, (u)int, float, double and their
//! synonyms (int8 … uint32); encodings raw, gzip and ascii; endian; `spacings` and `space
//! directions` (spacing = vector lengths); `data file` (one file, relative to the header);
//! `byte skip` (≥ 0, or -1 for raw: data at the end of the file) and `line skip`.
//! Not supported (clear error): other encodings (hex, bzip2, zstd), 64-bit integers,
//! block type, multi-file `data file` lists and patterns, dimensions other than 3.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{anyhow, bail, ensure, Context as _, Result};

use super::{
    build_volume, check_size, checked_dims, header_bytes, parse_ascii, parse_numbers,
    read_compressed, read_file, read_promised, resolve_spacing, LoadOptions, Sample,
};
use crate::volume::Volume;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Raw,
    Gzip,
    Ascii,
}

pub(super) fn load(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    let file = read_file(path)?;
    ensure!(
        file.starts_with(b"NRRD000"),
        "not an NRRD file (no 'NRRD000x' magic at the start)"
    );
    // The header ends at the first empty line; data follows it in an attached file.
    let blank = find_blank_line(&file);
    let (header_end, data_start) = blank.unwrap_or((file.len(), file.len()));
    let header = String::from_utf8_lossy(&file[..header_end]);
    let mut fields: HashMap<String, String> = HashMap::new();
    for line in header.lines().skip(1) {
        let line = line.trim_end_matches('\r');
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if let Some((k, _)) = line.split_once(":=") {
            if !k.contains(": ") {
                continue; // key/value pair, not a field
            }
        }
        let Some((k, v)) = line.split_once(": ") else {
            bail!(
                "malformed header line '{line}' (expected 'field: value'){}",
                if blank.is_none() {
                    "; truncated header?"
                } else {
                    ""
                }
            );
        };
        let key = k.trim().to_ascii_lowercase();
        ensure!(
            fields.insert(key.clone(), v.trim().to_string()).is_none(),
            "field '{key}' is given twice (which one is meant?)"
        );
    }
    let get = |k: &str| fields.get(k).map(String::as_str);

    let dimension: i64 = get("dimension")
        .ok_or_else(|| anyhow!("header has no 'dimension' field (truncated header?)"))?
        .parse()
        .map_err(|_| anyhow!("bad 'dimension' field"))?;
    ensure!(
        dimension == 3,
        "dimension {dimension} is not supported (only 3-D scalar volumes)"
    );
    let type_name = get("type").ok_or_else(|| anyhow!("header has no 'type' field"))?;
    let sample = parse_type(type_name)?;
    let sizes = get("sizes").ok_or_else(|| anyhow!("header has no 'sizes' field"))?;
    let sizes = parse_numbers::<i64>(sizes, "sizes")?;
    ensure!(
        sizes.len() == 3,
        "'sizes' has {} values, dimension is 3",
        sizes.len()
    );
    let dims = checked_dims([sizes[0], sizes[1], sizes[2]])?;
    let expected = header_bytes(dims, sample, opts)?;

    let encoding = match get("encoding")
        .ok_or_else(|| anyhow!("header has no 'encoding' field"))?
        .to_ascii_lowercase()
        .as_str()
    {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => bail!("unsupported encoding '{other}' (supported: raw, gzip, ascii)"),
    };
    let big_endian = match get("endian").map(|s| s.to_ascii_lowercase()) {
        Some(e) if e == "little" => false,
        Some(e) if e == "big" => true,
        Some(e) => bail!("bad endian '{e}' (little or big)"),
        None if sample.size() == 1 || encoding == Encoding::Ascii => false,
        None => bail!(
            "header has no 'endian' field, needed for {} data",
            sample.name()
        ),
    };
    let spacing = header_spacing(&fields)?;
    let line_skip: usize = match get("line skip").or(get("lineskip")) {
        Some(s) => s.parse().map_err(|_| anyhow!("bad 'line skip' '{s}'"))?,
        None => 0,
    };
    let byte_skip: i64 = match get("byte skip").or(get("byteskip")) {
        Some(s) => s.parse().map_err(|_| anyhow!("bad 'byte skip' '{s}'"))?,
        None => 0,
    };
    ensure!(
        byte_skip >= -1,
        "bad 'byte skip' {byte_skip} (must be -1 or more)"
    );

    // Where the data is: a detached file or after the header.
    let detached;
    let (data, what): (&[u8], String) = match get("data file").or(get("datafile")) {
        Some(name) => {
            ensure!(
                !name.contains('%') && !name.starts_with("LIST"),
                "'data file: {name}': multi-file data is not supported (one data file only)"
            );
            let dir = path.parent().unwrap_or(Path::new("."));
            let data_path = dir.join(name);
            // Raw data at a known offset: read no more than the header promises.
            detached = if encoding == Encoding::Raw && line_skip == 0 && byte_skip >= 0 {
                let promised = (byte_skip as u64).saturating_add(expected as u64);
                read_promised(&data_path, &format!("data file '{name}'"), promised)?
            } else {
                read_file(&data_path)?
            };
            (&detached, format!("data file '{name}'"))
        }
        None => {
            ensure!(
                header_end < file.len(),
                "header has no empty line ending it and no 'data file' (truncated header?)"
            );
            (&file[data_start..], "data after the header".to_string())
        }
    };

    let data =
        skip_lines(data, line_skip).with_context(|| format!("{what}: 'line skip: {line_skip}'"))?;
    let bytes: Vec<u8>;
    let payload: &[u8] = match encoding {
        Encoding::Raw => {
            let start = if byte_skip == -1 {
                ensure!(
                    data.len() >= expected,
                    "{what} is {} bytes, header says {expected} bytes (file too short: \
                     truncated?)",
                    data.len()
                );
                data.len() - expected
            } else {
                let skip = usize::try_from(byte_skip).unwrap_or(usize::MAX);
                ensure!(
                    skip <= data.len(),
                    "{what} is {} bytes, shorter than 'byte skip: {byte_skip}'",
                    data.len()
                );
                skip
            };
            check_size(&what, data.len() - start, expected)?;
            &data[start..]
        }
        Encoding::Gzip => {
            ensure!(
                byte_skip >= 0,
                "'byte skip: -1' is only allowed with raw encoding"
            );
            let skip = byte_skip as usize;
            let total = expected
                .checked_add(skip)
                .ok_or_else(|| anyhow!("byte skip too large"))?;
            bytes = read_compressed(flate2::read::MultiGzDecoder::new(data), "gzip", total)
                .with_context(|| what.clone())?;
            &bytes[skip..]
        }
        Encoding::Ascii => {
            let text = String::from_utf8_lossy(data);
            let n = expected / sample.size();
            bytes = parse_ascii(&text, sample, n).with_context(|| what.clone())?;
            &bytes
        }
    };
    let big_endian = big_endian && encoding != Encoding::Ascii;
    let stated = spacing.is_some() || opts.spacing.is_some();
    let spacing = resolve_spacing(opts, spacing)?;
    let mut volume = build_volume(dims, spacing, sample, big_endian, payload, None, opts)?;
    volume.spacing_stated = stated;
    volume.axes = header_axes(&fields);
    Ok(volume)
}

/// (end of header, start of data) for the first empty line.
fn find_blank_line(file: &[u8]) -> Option<(usize, usize)> {
    let mut i = 0;
    while i < file.len() {
        if file[i] == b'\n' {
            let rest = &file[i + 1..];
            if rest.starts_with(b"\n") {
                return Some((i + 1, i + 2));
            }
            if rest.starts_with(b"\r\n") {
                return Some((i + 1, i + 3));
            }
        }
        i += 1;
    }
    None
}

fn skip_lines(mut data: &[u8], n: usize) -> Result<&[u8]> {
    for i in 0..n {
        let nl = data
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| anyhow!("data ends after {i} lines"))?;
        data = &data[nl + 1..];
    }
    Ok(data)
}

fn parse_type(t: &str) -> Result<Sample> {
    let t = t.to_ascii_lowercase();
    Ok(match t.as_str() {
        "signed char" | "int8" | "int8_t" => Sample::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Sample::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            Sample::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Sample::U16,
        "int" | "signed int" | "int32" | "int32_t" => Sample::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => Sample::U32,
        "float" => Sample::F32,
        "double" => Sample::F64,
        _ => bail!("unsupported type '{t}' (supported: (u)char, (u)short, (u)int, float, double)"),
    })
}

/// The voxel axes in the patient's LPS frame from `space` (a patient space: LPS, RAS or
/// LAS, long or short names) and `space directions`; `None` when either is missing or the
/// space is not anatomical (scanner-xyz, 3D-right-handed...). Malformed fields are left
/// to [`header_spacing`] to report.
fn header_axes(fields: &HashMap<String, String>) -> Option<[[f32; 3]; 3]> {
    let sign: [f64; 3] = match fields.get("space")?.to_ascii_lowercase().as_str() {
        "left-posterior-superior" | "lps" => [1.0, 1.0, 1.0],
        "right-anterior-superior" | "ras" => [-1.0, -1.0, 1.0],
        "left-anterior-superior" | "las" => [1.0, -1.0, 1.0],
        _ => return None,
    };
    let mut axes = Vec::new();
    for part in fields.get("space directions")?.split(')') {
        if part.trim().is_empty() {
            continue;
        }
        let inner = part.trim().strip_prefix('(')?;
        let v = parse_numbers::<f64>(inner, "space directions").ok()?;
        let v: [f64; 3] = v.try_into().ok()?;
        let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(l.is_finite() && l > 0.0) {
            return None;
        }
        axes.push(std::array::from_fn(|i| (sign[i] * v[i] / l) as f32));
    }
    axes.try_into().ok()
}

/// Spacing from `space directions` (vector lengths) or `spacings`.
fn header_spacing(fields: &HashMap<String, String>) -> Result<Option<[f64; 3]>> {
    ensure!(
        !(fields.contains_key("space directions") && fields.contains_key("spacings")),
        "both 'space directions' and 'spacings' are given; the NRRD format allows one \
         (the directions' lengths are the spacing)"
    );
    if let Some(dirs) = fields.get("space directions") {
        let mut out = Vec::new();
        let mut rest = dirs.as_str().trim();
        while !rest.is_empty() {
            ensure!(
                !rest.starts_with("none"),
                "'space directions' has 'none' for a spatial axis: '{dirs}'"
            );
            let open = rest
                .strip_prefix('(')
                .ok_or_else(|| anyhow!("malformed 'space directions': '{dirs}'"))?;
            let close = open
                .find(')')
                .ok_or_else(|| anyhow!("malformed 'space directions': '{dirs}'"))?;
            let v = parse_numbers::<f64>(&open[..close], "space directions")?;
            out.push(v.iter().map(|x| x * x).sum::<f64>().sqrt());
            rest = open[close + 1..].trim_start();
        }
        ensure!(
            out.len() == 3,
            "'space directions' has {} vectors, dimension is 3",
            out.len()
        );
        return Ok(Some([out[0], out[1], out[2]]));
    }
    if let Some(sp) = fields.get("spacings") {
        let v = parse_numbers::<f64>(sp, "spacings")?;
        ensure!(
            v.len() == 3,
            "'spacings' has {} values, dimension is 3",
            v.len()
        );
        return Ok(Some([v[0].abs(), v[1].abs(), v[2].abs()]));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_and_spacing_fields() {
        assert_eq!(parse_type("short").unwrap(), Sample::I16);
        assert_eq!(parse_type("unsigned char").unwrap(), Sample::U8);
        assert_eq!(parse_type("double").unwrap(), Sample::F64);
        let e = parse_type("int64").unwrap_err().to_string();
        assert!(e.contains("unsupported type"), "{e}");

        let mut f = HashMap::new();
        f.insert(
            "space directions".to_string(),
            "(0.5,0,0) (0,3,4) (0,0,-2.5e0)".to_string(),
        );
        assert_eq!(header_spacing(&f).unwrap(), Some([0.5, 5.0, 2.5]));
        f.clear();
        f.insert("spacings".into(), "1 2 3".into());
        assert_eq!(header_spacing(&f).unwrap(), Some([1.0, 2.0, 3.0]));
        f.insert("space directions".into(), "none (1,0,0) (0,1,0)".into());
        assert!(header_spacing(&f).is_err());
    }

    #[test]
    fn blank_line_and_line_skip() {
        assert_eq!(find_blank_line(b"NRRD0004\na: b\n\nDATA"), Some((14, 15)));
        assert_eq!(
            find_blank_line(b"NRRD0004\r\na: b\r\n\r\nDATA"),
            Some((16, 18))
        );
        assert_eq!(find_blank_line(b"NRRD0004\na: b\n"), None);
        assert_eq!(skip_lines(b"x\ny\nz", 2).unwrap(), b"z");
        assert!(skip_lines(b"x\ny", 2).is_err());
    }
}

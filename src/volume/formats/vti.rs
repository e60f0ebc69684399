//! VTK XML ImageData (`.vti`): one piece, the first (or the `Scalars`-named) PointData
//! DataArray.
//!
//! Supported: `WholeExtent`, `Spacing`, `Direction` (the orientation); DataArray types Int8, UInt8, Int16, UInt16, Int32,
//! UInt32, Float32, Float64 with one component; formats `ascii`, `binary` (inline base64)
//! and `appended` (`encoding="raw"` or `"base64"`, the `_` marker, `offset`);
//! `header_type` UInt32 (default) or UInt64; `byte_order` LittleEndian or BigEndian; no
//! compressor or `vtkZLibDataCompressor` (block headers). Base64 header and data are read
//! whether they were encoded as one stream (VTK, uncompressed) or separately (VTK,
//! compressed).
//! Not supported (clear error): other compressors (LZ4, LZMA), several pieces, CellData,
//! several components, 64-bit integer and string arrays.
//!
//! The XML is read with a small tag scanner rather than an XML crate: appended raw data is
//! not XML, and only a handful of elements and attributes matter.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{anyhow, bail, ensure, Context as _, Result};
use base64::Engine as _;

use super::{
    build_volume, checked_dims, parse_ascii, parse_numbers, read_compressed, read_file,
    resolve_spacing, LoadOptions, Sample,
};
use crate::volume::orientation::{unit_axes, world_to_lps};
use crate::volume::Volume;

struct Tag {
    name: String,
    attrs: HashMap<String, String>,
    closing: bool,
    self_closing: bool,
    /// Byte offset just after the tag's `>`.
    end: usize,
}

/// Scans the next tag at or after `pos`; `None` at the end of the input.
fn next_tag(s: &[u8], mut pos: usize) -> Result<Option<Tag>> {
    loop {
        let Some(lt) = s[pos.min(s.len())..].iter().position(|&b| b == b'<') else {
            return Ok(None);
        };
        pos += lt;
        let rest = &s[pos..];
        // Processing instructions and comments.
        let skip_to = |end: &[u8]| -> Result<usize> {
            rest.windows(end.len())
                .position(|w| w == end)
                .map(|i| pos + i + end.len())
                .ok_or_else(|| anyhow!("unterminated XML markup at byte {pos}"))
        };
        if rest.starts_with(b"<?") {
            pos = skip_to(b"?>")?;
            continue;
        }
        if rest.starts_with(b"<!--") {
            pos = skip_to(b"-->")?;
            continue;
        }
        if rest.starts_with(b"<!") {
            pos = skip_to(b">")?;
            continue;
        }
        let mut i = 1;
        let closing = rest.get(1) == Some(&b'/');
        if closing {
            i += 1;
        }
        let name_start = i;
        while i < rest.len() && !rest[i].is_ascii_whitespace() && rest[i] != b'>' && rest[i] != b'/'
        {
            i += 1;
        }
        let name = String::from_utf8_lossy(&rest[name_start..i]).into_owned();
        let mut attrs = HashMap::new();
        loop {
            while i < rest.len() && rest[i].is_ascii_whitespace() {
                i += 1;
            }
            match rest.get(i) {
                None => bail!("unterminated XML tag <{name}> at byte {pos} (truncated file?)"),
                Some(b'>') => {
                    return Ok(Some(Tag {
                        name,
                        attrs,
                        closing,
                        self_closing: false,
                        end: pos + i + 1,
                    }))
                }
                Some(b'/') if rest.get(i + 1) == Some(&b'>') => {
                    return Ok(Some(Tag {
                        name,
                        attrs,
                        closing,
                        self_closing: true,
                        end: pos + i + 2,
                    }))
                }
                _ => {}
            }
            let k0 = i;
            while i < rest.len()
                && rest[i] != b'='
                && rest[i] != b'>'
                && !rest[i].is_ascii_whitespace()
            {
                i += 1;
            }
            let key = String::from_utf8_lossy(&rest[k0..i]).into_owned();
            while i < rest.len() && rest[i].is_ascii_whitespace() {
                i += 1;
            }
            ensure!(
                rest.get(i) == Some(&b'='),
                "malformed XML attribute '{key}' in <{name}> at byte {pos}"
            );
            i += 1;
            while i < rest.len() && rest[i].is_ascii_whitespace() {
                i += 1;
            }
            let quote = *rest
                .get(i)
                .ok_or_else(|| anyhow!("unterminated XML tag <{name}> (truncated file?)"))?;
            ensure!(
                quote == b'"' || quote == b'\'',
                "malformed XML attribute '{key}' in <{name}>: value not quoted"
            );
            let v0 = i + 1;
            let len = rest[v0..]
                .iter()
                .position(|&b| b == quote)
                .ok_or_else(|| anyhow!("unterminated XML attribute '{key}' in <{name}>"))?;
            attrs.insert(
                key,
                String::from_utf8_lossy(&rest[v0..v0 + len]).into_owned(),
            );
            i = v0 + len + 1;
        }
    }
}

struct Array {
    attrs: HashMap<String, String>,
    /// Text content (for ascii and binary formats).
    text: (usize, usize),
}

pub(super) fn load(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    let file = read_file(path)?;
    let mut vtkfile = None;
    let mut image = None;
    let mut pieces = 0;
    let mut in_point_data = false;
    let mut scalars_name = None;
    let mut arrays: Vec<Array> = Vec::new();
    let mut appended: Option<(usize, String)> = None;
    let mut pos = 0;
    while let Some(tag) = next_tag(&file, pos)? {
        pos = tag.end;
        if tag.closing {
            if tag.name == "PointData" {
                in_point_data = false;
            }
            continue;
        }
        match tag.name.as_str() {
            "VTKFile" => vtkfile = Some(tag.attrs),
            "ImageData" => image = Some(tag.attrs),
            "Piece" => pieces += 1,
            "PointData" if !tag.self_closing => {
                in_point_data = true;
                scalars_name = tag.attrs.get("Scalars").cloned();
            }
            "DataArray" if in_point_data => {
                let mut text = (tag.end, tag.end);
                if !tag.self_closing {
                    let close = file[tag.end..]
                        .iter()
                        .position(|&b| b == b'<')
                        .ok_or_else(|| anyhow!("DataArray has no closing tag (truncated?)"))?;
                    text.1 = tag.end + close;
                    pos = text.1;
                }
                arrays.push(Array {
                    attrs: tag.attrs,
                    text,
                });
            }
            "AppendedData" => {
                let enc = tag
                    .attrs
                    .get("encoding")
                    .cloned()
                    .unwrap_or_else(|| "raw".into());
                let us = file[tag.end..]
                    .iter()
                    .position(|&b| b == b'_')
                    .ok_or_else(|| anyhow!("AppendedData has no '_' marker (truncated?)"))?;
                appended = Some((tag.end + us + 1, enc));
                break; // everything after the marker is data, not XML
            }
            _ => {}
        }
    }

    let vtkfile = vtkfile.ok_or_else(|| anyhow!("no <VTKFile> element (not a VTK XML file?)"))?;
    let ty = vtkfile.get("type").map(String::as_str).unwrap_or("");
    ensure!(ty == "ImageData", "VTKFile type '{ty}' is not ImageData");
    let big_endian = match vtkfile.get("byte_order").map(String::as_str) {
        None | Some("LittleEndian") => false,
        Some("BigEndian") => true,
        Some(o) => bail!("bad byte_order '{o}'"),
    };
    let header_bytes = match vtkfile.get("header_type").map(String::as_str) {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(h) => bail!("unsupported header_type '{h}' (UInt32 or UInt64)"),
    };
    let compressed = match vtkfile.get("compressor").map(String::as_str) {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => bail!("unsupported compressor '{c}' (only vtkZLibDataCompressor)"),
    };
    let image = image.ok_or_else(|| anyhow!("no <ImageData> element"))?;
    ensure!(pieces <= 1, "{pieces} pieces are not supported (only one)");
    let extent = image
        .get("WholeExtent")
        .ok_or_else(|| anyhow!("ImageData has no WholeExtent"))?;
    let e = parse_numbers::<i64>(extent, "WholeExtent")?;
    ensure!(
        e.len() == 6,
        "WholeExtent has {} values, expected 6",
        e.len()
    );
    let d = |i: usize| {
        e[2 * i + 1]
            .checked_sub(e[2 * i])
            .and_then(|x| x.checked_add(1))
            .unwrap_or(0)
    };
    let dims = checked_dims([d(0), d(1), d(2)])?;
    let spacing = match image.get("Spacing") {
        Some(s) => {
            let v = parse_numbers::<f64>(s, "Spacing")?;
            ensure!(v.len() == 3, "Spacing has {} values, expected 3", v.len());
            Some([v[0], v[1], v[2]])
        }
        None => None,
    };

    ensure!(
        !arrays.is_empty(),
        "no PointData DataArray (CellData is not supported)"
    );
    let array = match &scalars_name {
        Some(n) => arrays
            .iter()
            .find(|a| a.attrs.get("Name") == Some(n))
            .unwrap_or(&arrays[0]),
        None => &arrays[0],
    };
    let name = array.attrs.get("Name").cloned().unwrap_or_default();
    let tname = array.attrs.get("type").map(String::as_str).unwrap_or("");
    let sample = match tname {
        "Int8" | "Char" => Sample::I8,
        "UInt8" | "UnsignedChar" => Sample::U8,
        "Int16" | "Short" => Sample::I16,
        "UInt16" | "UnsignedShort" => Sample::U16,
        "Int32" | "Int" => Sample::I32,
        "UInt32" | "UnsignedInt" => Sample::U32,
        "Float32" | "Float" => Sample::F32,
        "Float64" | "Double" => Sample::F64,
        _ => bail!(
            "DataArray '{name}' has unsupported type '{tname}' (supported: Int8, UInt8, Int16, \
             UInt16, Int32, UInt32, Float32, Float64)"
        ),
    };
    if let Some(c) = array.attrs.get("NumberOfComponents") {
        ensure!(
            c.trim() == "1",
            "DataArray '{name}' has {c} components (only scalar data is supported)"
        );
    }
    let expected = super::header_bytes(dims, sample, opts)?;
    let format = array.attrs.get("format").map(String::as_str).unwrap_or("");
    let what = format!("DataArray '{name}'");
    let text = &file[array.text.0..array.text.1];
    let (bytes, be) = match format {
        "ascii" => {
            let t = String::from_utf8_lossy(text);
            (parse_ascii(&t, sample, expected / sample.size())?, false)
        }
        "binary" => {
            let chars: Vec<u8> = text
                .iter()
                .copied()
                .filter(|b| !b.is_ascii_whitespace())
                .collect();
            let src = Source::Base64(&chars);
            (
                read_block(src, header_bytes, big_endian, compressed, expected)
                    .with_context(|| what.clone())?,
                big_endian,
            )
        }
        "appended" => {
            let (start, enc) = appended
                .as_ref()
                .ok_or_else(|| anyhow!("{what} is appended but there is no AppendedData"))?;
            let offset: usize = array
                .attrs
                .get("offset")
                .ok_or_else(|| anyhow!("{what} is appended but has no offset"))?
                .trim()
                .parse()
                .map_err(|_| anyhow!("{what} has a bad offset"))?;
            let all = &file[*start..];
            ensure!(
                offset <= all.len(),
                "{what}: offset {offset} is past the end of the appended data ({} bytes; \
                 truncated file?)",
                all.len()
            );
            let src = match enc.as_str() {
                "raw" => Source::Raw(&all[offset..]),
                "base64" => Source::Base64(&all[offset..]),
                e => bail!("unsupported AppendedData encoding '{e}' (raw or base64)"),
            };
            (
                read_block(src, header_bytes, big_endian, compressed, expected)
                    .with_context(|| what.clone())?,
                big_endian,
            )
        }
        f => bail!("{what} has unsupported format '{f}' (ascii, binary or appended)"),
    };
    let stated = spacing.is_some() || opts.spacing.is_some();
    let spacing = resolve_spacing(opts, spacing)?;
    let mut volume = build_volume(dims, spacing, sample, be, &bytes, None, opts)?;
    volume.spacing_stated = stated;
    volume.axes = match image.get("Direction") {
        Some(d) => Some(direction_axes(d)?),
        None => None,
    };
    Ok(volume)
}

/// The voxel axes from ImageData's `Direction` (VTK 9: the 3 × 3 direction matrix, row
/// by row; column k is voxel axis k in VTK's world). VTK's world has no anatomy, so the
/// axes are placed in the renderer's world as they were in VTK's (x right, y up, z
/// towards the viewer): the identity changes nothing, a rotated grid is turned back
/// upright ([`world_to_lps`]). `--orientation` states an anatomical one instead.
fn direction_axes(d: &str) -> Result<[[f32; 3]; 3]> {
    let v = parse_numbers::<f64>(d, "Direction")?;
    ensure!(v.len() == 9, "Direction has {} values, expected 9", v.len());
    let columns = std::array::from_fn(|k| std::array::from_fn(|r| v[3 * r + k]));
    let axes = unit_axes(columns)
        .ok_or_else(|| anyhow!("Direction '{d}' is degenerate (no orientation)"))?;
    Ok(axes.map(world_to_lps))
}

#[derive(Clone, Copy)]
enum Source<'a> {
    /// Raw bytes starting at the block's header.
    Raw(&'a [u8]),
    /// Base64 characters starting at the block's header.
    Base64(&'a [u8]),
}

fn b64(chars: &[u8]) -> Result<Vec<u8>> {
    base64::engine::general_purpose::STANDARD
        .decode(chars)
        .map_err(|e| anyhow!("bad base64 data: {e}"))
}

/// Base64 characters encoding `n` bytes.
fn b64_len(n: usize) -> Result<usize> {
    n.div_ceil(3)
        .checked_mul(4)
        .ok_or_else(|| anyhow!("size overflows"))
}

fn uint(bytes: &[u8], be: bool) -> u64 {
    let mut v = 0u64;
    if be {
        for &b in bytes {
            v = (v << 8) | b as u64;
        }
    } else {
        for &b in bytes.iter().rev() {
            v = (v << 8) | b as u64;
        }
    }
    v
}

/// Takes `n` bytes (raw) / the characters encoding them (base64) from `src` at `at`.
fn take<'a>(src: &'a [u8], at: usize, n: usize, unit: &str) -> Result<&'a [u8]> {
    let end = at.checked_add(n).ok_or_else(|| anyhow!("size overflows"))?;
    ensure!(
        end <= src.len(),
        "data ends after {} {unit}, the block needs {end} (truncated file?)",
        src.len()
    );
    Ok(&src[at..end])
}

/// Reads the header words and payload of one binary block: the header is `header_len`
/// bytes, whose first `prefix` bytes tell the payload size (via `payload_len`).
fn split_block(
    src: Source,
    prefix: usize,
    header_len: &dyn Fn(&[u8]) -> Result<usize>,
    payload_len: &dyn Fn(&[u8]) -> Result<usize>,
) -> Result<(Vec<u8>, Vec<u8>)> {
    match src {
        Source::Raw(s) => {
            let first = take(s, 0, prefix, "bytes")?;
            let h = header_len(first)?;
            let header = take(s, 0, h, "bytes")?;
            let p = payload_len(header)?;
            let payload = take(s, h, p, "bytes")?;
            Ok((header.to_vec(), payload.to_vec()))
        }
        Source::Base64(s) => {
            // `prefix` is a multiple of 3 bytes (3 header words), or a single word whose
            // quartets decode fine either way; decode the characters that cover it.
            let pre_chars = b64_len(prefix)?;
            let pre = b64(take(s, 0, pre_chars, "base64 characters")?)?;
            let h = header_len(&pre[..prefix.min(pre.len())])?;
            let h_chars = b64_len(h)?;
            // VTK encodes the header and the payload as separate base64 streams when it
            // compresses, as one stream when it does not. They differ only when the header
            // is not a multiple of 3 bytes, and then the separate header ends in '='.
            let separate = h % 3 == 0 || take(s, 0, h_chars, "base64 characters")?.ends_with(b"=");
            if separate {
                let header = b64(take(s, 0, h_chars, "base64 characters")?)?;
                let p = payload_len(&header)?;
                let payload = b64(take(s, h_chars, b64_len(p)?, "base64 characters")?)?;
                ensure!(
                    payload.len() == p,
                    "base64 payload decodes to {} bytes, expected {p}",
                    payload.len()
                );
                Ok((header, payload))
            } else {
                // One stream: the payload size is in the first word.
                let first = b64(take(s, 0, b64_len(h)?.max(4), "base64 characters")?)?;
                let p = payload_len(&first[..h.min(first.len())])?;
                let total = h.checked_add(p).ok_or_else(|| anyhow!("size overflows"))?;
                let all = b64(take(s, 0, b64_len(total)?, "base64 characters")?)?;
                ensure!(
                    all.len() == total,
                    "base64 block decodes to {} bytes, expected {total}",
                    all.len()
                );
                let payload = all[h..].to_vec();
                let mut header = all;
                header.truncate(h);
                Ok((header, payload))
            }
        }
    }
}

/// Reads one array's bytes: header + data, or header + zlib blocks.
fn read_block(
    src: Source,
    hb: usize,
    be: bool,
    compressed: bool,
    expected: usize,
) -> Result<Vec<u8>> {
    let to_usize =
        |v: u64, what: &str| usize::try_from(v).map_err(|_| anyhow!("{what} {v} is too large"));
    if !compressed {
        let header_len = |_: &[u8]| Ok(hb);
        let payload_len = |h: &[u8]| -> Result<usize> {
            ensure!(h.len() >= hb, "block header is truncated");
            let n = to_usize(uint(&h[..hb], be), "byte count")?;
            ensure!(
                n == expected,
                "holds {n} bytes, but WholeExtent and type need {expected} bytes"
            );
            Ok(n)
        };
        let (_, payload) = split_block(src, hb, &header_len, &payload_len)?;
        return Ok(payload);
    }
    // Compressed: [nblocks, block size, last block size, compressed size × nblocks].
    let nblocks = |h: &[u8]| -> Result<usize> {
        ensure!(h.len() >= 3 * hb, "compression header is truncated");
        to_usize(uint(&h[..hb], be), "block count")
    };
    let header_len = |h: &[u8]| -> Result<usize> {
        let nb = nblocks(h)?;
        nb.checked_add(3)
            .and_then(|w| w.checked_mul(hb))
            .ok_or_else(|| anyhow!("block count {nb} is too large"))
    };
    let word = |h: &[u8], i: usize| uint(&h[i * hb..(i + 1) * hb], be);
    let payload_len = |h: &[u8]| -> Result<usize> {
        let nb = nblocks(h)?;
        ensure!(h.len() >= (3 + nb) * hb, "compression header is truncated");
        let mut sum = 0usize;
        for i in 0..nb {
            sum = sum
                .checked_add(to_usize(word(h, 3 + i), "compressed block size")?)
                .ok_or_else(|| anyhow!("compressed sizes overflow"))?;
        }
        Ok(sum)
    };
    let (header, payload) = split_block(src, 3 * hb, &header_len, &payload_len)?;
    let nb = nblocks(&header)?;
    let block = to_usize(word(&header, 1), "block size")?;
    let last = to_usize(word(&header, 2), "last block size")?;
    let last = if last == 0 { block } else { last };
    let total = if nb == 0 {
        0
    } else {
        (nb - 1)
            .checked_mul(block)
            .and_then(|x| x.checked_add(last))
            .ok_or_else(|| anyhow!("block sizes overflow"))?
    };
    ensure!(
        total == expected,
        "holds {total} bytes ({nb} compressed blocks), but WholeExtent and type need {expected} \
         bytes"
    );
    ensure!(
        nb == 0 || last <= block,
        "last block size {last} exceeds block size {block}"
    );
    let mut out = Vec::with_capacity(expected.min(payload.len().saturating_mul(1032)));
    let mut at = 0usize;
    for i in 0..nb {
        let cs = to_usize(word(&header, 3 + i), "compressed block size")?;
        let chunk = &payload[at..at + cs];
        at += cs;
        let want = if i + 1 == nb { last } else { block };
        let data = read_compressed(flate2::read::ZlibDecoder::new(chunk), "zlib", want)
            .with_context(|| format!("block {i}"))?;
        out.extend_from_slice(&data);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tag_scanner() {
        let s = br#"<?xml version="1.0"?><!-- c --><A x="1" y = '2'><B/></A>"#;
        let t = next_tag(s, 0).unwrap().unwrap();
        assert_eq!(t.name, "A");
        assert_eq!(t.attrs["x"], "1");
        assert_eq!(t.attrs["y"], "2");
        let t = next_tag(s, t.end).unwrap().unwrap();
        assert!(t.self_closing && t.name == "B");
        let t = next_tag(s, t.end).unwrap().unwrap();
        assert!(t.closing && t.name == "A");
        assert!(next_tag(s, t.end).unwrap().is_none());
        assert!(next_tag(b"<A x=\"1", 0).is_err());
        assert!(next_tag(b"<A x=1>", 0).is_err());
    }

    #[test]
    fn base64_block_joint_and_separate() {
        let data = [1u8, 2, 3, 4, 5];
        let e = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
        let header = 5u32.to_le_bytes();
        // One stream (VTK uncompressed).
        let joint = e(&[&header[..], &data].concat());
        let got = read_block(Source::Base64(joint.as_bytes()), 4, false, false, 5).unwrap();
        assert_eq!(got, data);
        // Separate streams.
        let sep = e(&header) + &e(&data);
        let got = read_block(Source::Base64(sep.as_bytes()), 4, false, false, 5).unwrap();
        assert_eq!(got, data);
        // UInt64 header.
        let sep = e(&5u64.to_le_bytes()) + &e(&data);
        let got = read_block(Source::Base64(sep.as_bytes()), 8, false, false, 5).unwrap();
        assert_eq!(got, data);
        let joint = e(&[&5u64.to_le_bytes()[..], &data].concat());
        let got = read_block(Source::Base64(joint.as_bytes()), 8, false, false, 5).unwrap();
        assert_eq!(got, data);
        // Wrong size.
        let e = read_block(Source::Base64(sep.as_bytes()), 8, false, false, 6).unwrap_err();
        assert!(e.to_string().contains("need 6 bytes"), "{e}");
    }
}

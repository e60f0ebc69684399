//! Headerless raw files: an explicit [`RawLayout`], or the open-scivis naming
//! `<name>_<X>x<Y>x<Z>_<type>.raw` (types uint8, uint16, int16, float32; little-endian).

use std::path::Path;

use anyhow::{anyhow, bail, ensure, Context as _, Result};

use super::{
    build_volume, check_size, checked_dims, header_bytes, read_file, resolve_spacing, LoadOptions,
    RawLayout, ScalarKind,
};
use crate::volume::Volume;

/// Reads `path` with an explicit layout.
pub(super) fn load(path: &Path, layout: &RawLayout, opts: &LoadOptions) -> Result<Volume> {
    let dims = checked_dims(layout.dims.map(i64::from))?;
    let sample = layout.kind.sample();
    let expected = header_bytes(dims, sample, opts)?;
    let len = std::fs::metadata(path)
        .map_err(|e| anyhow!("cannot read '{}': {e}", path.display()))?
        .len();
    if len != expected as u64 {
        bail!(
            "raw file is {len} bytes, but {}x{}x{} {} voxels ({} bytes each) need {expected} \
             bytes",
            dims[0],
            dims[1],
            dims[2],
            sample.name(),
            sample.size()
        );
    }
    let bytes = read_file(path)?;
    check_size("raw file", bytes.len(), expected)?;
    let sidecar = match (opts.spacing, layout.spacing) {
        (None, None) => sidecar_spacing(path, dims)?,
        _ => None,
    };
    let spacing = match (opts.spacing, layout.spacing, &sidecar) {
        (None, Some(s), _) => {
            ensure!(
                s.iter().all(|x| x.is_finite() && *x > 0.0),
                "raw layout spacing {s:?} must be finite and positive"
            );
            s
        }
        (None, None, Some((s, _))) => *s,
        _ => resolve_spacing(opts, None)?,
    };
    let mut volume = build_volume(dims, spacing, sample, false, &bytes, None, opts)?;
    volume.spacing_stated = opts.spacing.is_some() || layout.spacing.is_some() || sidecar.is_some();
    Ok(volume)
}

/// The JSON files beside a raw file that may describe it: `<name>.json` for
/// `<name>_<X>x<Y>x<Z>_<type>.raw` (as the open-scivis collection names its
/// descriptions) and `<file stem>.json`.
pub(crate) fn sidecar_paths(path: &Path) -> Vec<std::path::PathBuf> {
    let Some(stem) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
        return Vec::new();
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut names = Vec::new();
    let mut parts = stem.rsplitn(3, '_');
    if let (Some(_), Some(_), Some(base)) = (parts.next(), parts.next(), parts.next()) {
        names.push(format!("{base}.json"));
    }
    names.push(format!("{stem}.json"));
    names.into_iter().map(|n| dir.join(n)).collect()
}

/// The spacing a JSON sidecar states (`"spacing": [x, y, z]`), with the sidecar's path.
/// A sidecar whose `"size"` differs from the file's dimensions describes another file:
/// an error, as is a sidecar that is not JSON or whose spacing is malformed. `None` when
/// there is no sidecar or it states no spacing.
fn sidecar_spacing(path: &Path, dims: [u32; 3]) -> Result<Option<([f32; 3], std::path::PathBuf)>> {
    let Some(json) = sidecar_paths(path).into_iter().find(|p| p.is_file()) else {
        return Ok(None);
    };
    let what = || format!("the sidecar {}", json.display());
    // A description is a few hundred bytes: read no more than a megabyte of it.
    let text = super::read_promised(&json, &what(), 1 << 20)?;
    let value: serde_json::Value =
        serde_json::from_slice(&text).with_context(|| format!("{}: not JSON", what()))?;
    if let Some(size) = value.get("size") {
        let size: Option<Vec<u64>> = size
            .as_array()
            .map(|a| a.iter().filter_map(|v| v.as_u64()).collect());
        let matches = size.as_deref() == Some(&dims.map(u64::from)[..]);
        ensure!(
            matches,
            "{}: \"size\" {} is not the raw file's {}x{}x{}: it describes another file",
            what(),
            value["size"],
            dims[0],
            dims[1],
            dims[2]
        );
    }
    let Some(spacing) = value.get("spacing") else {
        return Ok(None);
    };
    let s: Option<Vec<f64>> = spacing
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_f64()).collect());
    let s = match s.as_deref() {
        Some(&[x, y, z]) if [x, y, z].iter().all(|v| v.is_finite() && *v > 0.0) => {
            [x as f32, y as f32, z as f32]
        }
        _ => bail!(
            "{}: \"spacing\" {spacing} is not three positive numbers",
            what()
        ),
    };
    Ok(Some((s, json)))
}

/// Reads a `.raw` file whose layout is in its name.
pub(super) fn load_named(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let layout = layout_from_name(&name)?;
    load(path, &layout, opts)
}

/// Parses `<name>_<X>x<Y>x<Z>_<type>.raw`.
pub(crate) fn layout_from_name(name: &str) -> Result<RawLayout> {
    let no_layout = || {
        anyhow!(
            "the raw file's layout is unknown: name it <name>_<X>x<Y>x<Z>_<type>.raw (type \
             uint8, uint16, int16 or float32) or give the layout explicitly"
        )
    };
    let lower = name.to_ascii_lowercase();
    let stem = lower.strip_suffix(".raw").ok_or_else(no_layout)?;
    let mut parts = stem.rsplitn(3, '_');
    let (Some(ty), Some(dims), Some(base)) = (parts.next(), parts.next(), parts.next()) else {
        return Err(no_layout());
    };
    if base.is_empty() {
        return Err(no_layout());
    }
    let d: Vec<&str> = dims.split('x').collect();
    if d.len() != 3
        || d.iter()
            .any(|s| s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()))
    {
        return Err(no_layout());
    }
    let mut parsed = [0i64; 3];
    for (p, s) in parsed.iter_mut().zip(&d) {
        *p = s
            .parse()
            .map_err(|_| anyhow!("dimension '{s}' in the file name is too large"))?;
    }
    let dims = checked_dims(parsed)?;
    let kind = ScalarKind::parse(ty).ok_or_else(|| {
        anyhow!(
            "type '{ty}' in the file name is not supported for raw files (supported: uint8, \
             uint16, int16, float32; convert the file or use a format with a header)"
        )
    })?;
    Ok(RawLayout {
        dims,
        kind,
        spacing: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_scivis_names() {
        let l = layout_from_name("bonsai_256x256x256_uint8.raw").unwrap();
        assert_eq!(l.dims, [256, 256, 256]);
        assert_eq!(l.kind, ScalarKind::U8);
        let l = layout_from_name("richtmyer_meshkov_2048x2048x1920_uint8.raw").unwrap();
        assert_eq!(l.dims, [2048, 2048, 1920]);
        let l = layout_from_name("lung1_512x512x48_int16.raw").unwrap();
        assert_eq!((l.dims, l.kind), ([512, 512, 48], ScalarKind::I16));
        let l = layout_from_name("x_3x4x5_FLOAT32.RAW").unwrap();
        assert_eq!(l.kind, ScalarKind::F32);
        let e = layout_from_name("jet_48x48x48_float64.raw")
            .unwrap_err()
            .to_string();
        assert!(e.contains("float64") && e.contains("not supported"), "{e}");
        for bad in [
            "bonsai.raw",
            "a_256x256_uint8.raw",
            "_8x8x8_uint8.raw",
            "a_8xx8_uint8.raw",
        ] {
            let e = layout_from_name(bad).unwrap_err().to_string();
            assert!(e.contains("layout is unknown"), "{bad}: {e}");
        }
        let e = layout_from_name("a_8x0x8_uint8.raw")
            .unwrap_err()
            .to_string();
        assert!(e.contains("non-positive"), "{e}");
        let e = layout_from_name("a_8x99999999999999999999x8_uint8.raw")
            .unwrap_err()
            .to_string();
        assert!(e.contains("too large"), "{e}");
    }
}

//! NIfTI-1 single files, `.nii` and gzip'd `.nii.gz` (magic `n+1`), either byte order.
//!
//! Supported: datatypes uint8, int8, int16, uint16, int32, uint32, float32, float64;
//! `pixdim[1..3]` as spacing; `scl_slope`/`scl_inter` (slope 0 means no scaling, as the
//! standard says); `vox_offset`. Up to 3 dimensions (a 4th or higher of size 1 is
//! accepted). Not supported (clear error): NIfTI-2, `.hdr`/`.img` pairs (magic `ni1`),
//! time series, complex/RGB/64-bit integer datatypes.

use std::io::Read;
use std::path::Path;

use anyhow::{anyhow, bail, ensure, Result};

use super::{
    build_volume, check_size, checked_dims, header_bytes, read_file_at_most, read_promised,
    resolve_spacing, LoadOptions, Rescale, Sample,
};
use crate::volume::Volume;

const HEADER: usize = 348;

pub(super) fn load(path: &Path, opts: &LoadOptions) -> Result<Volume> {
    let gz = path
        .file_name()
        .is_some_and(|n| n.to_string_lossy().to_ascii_lowercase().ends_with(".gz"));
    if gz {
        let f = std::fs::File::open(path)
            .map_err(|e| anyhow!("cannot read '{}': {e}", path.display()))?;
        let mut reader = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(f));
        let mut head = Vec::with_capacity(HEADER);
        (&mut reader)
            .take(HEADER as u64)
            .read_to_end(&mut head)
            .map_err(|e| anyhow!("gzip data is corrupt: {e}"))?;
        ensure!(
            head.len() == HEADER,
            "truncated header: the file decompresses to {} bytes, a NIfTI-1 header is {HEADER}",
            head.len()
        );
        let h = Header::parse(&head)?;
        let total = h.data_end(opts)?;
        let mut file = head;
        // Read at most one byte more than the header says, so a lying header allocates
        // only what is really there.
        (&mut reader)
            .take((total - HEADER) as u64 + 1)
            .read_to_end(&mut file)
            .map_err(|e| anyhow!("gzip data is corrupt: {e}"))?;
        finish(&h, &file, "decompressed file", true, opts)
    } else {
        // The header first: a volume the device cannot hold is refused before its data
        // is read, and at most one byte more than the header promises is read.
        let head = read_file_at_most(path, Some(HEADER as u64))?;
        ensure!(
            head.len() >= HEADER,
            "truncated header: the file is {} bytes, a NIfTI-1 header is {HEADER}",
            head.len()
        );
        let h = Header::parse(&head)?;
        let total = h.data_end(opts)?;
        let file = read_promised(path, "file", total as u64)?;
        finish(&h, &file, "file", false, opts)
    }
}

/// `capped`: `file` was read with a limit of one byte more than the header says.
fn finish(h: &Header, file: &[u8], what: &str, capped: bool, opts: &LoadOptions) -> Result<Volume> {
    let total = h.data_end(opts)?;
    ensure!(
        !(capped && file.len() > total),
        "{what} is more than {total} bytes, header says {total} bytes (file too long)"
    );
    ensure!(
        file.len() >= h.vox_offset,
        "{what} is {} bytes, shorter than vox_offset {} (truncated?)",
        file.len(),
        h.vox_offset
    );
    check_size(what, file.len(), total)?;
    let spacing = resolve_spacing(opts, Some(h.pixdim))?;
    let data = &file[h.vox_offset..total];
    let mut volume = build_volume(
        h.dims,
        spacing,
        h.sample,
        h.big_endian,
        data,
        h.rescale,
        opts,
    )?;
    volume.axes = h.axes;
    Ok(volume)
}

#[derive(Debug)]
struct Header {
    big_endian: bool,
    dims: [u32; 3],
    sample: Sample,
    pixdim: [f64; 3],
    vox_offset: usize,
    rescale: Option<Rescale>,
    /// Voxel axes in LPS (from the sform, else the qform; `None` if neither is set).
    axes: Option<[[f32; 3]; 3]>,
}

impl Header {
    fn parse(h: &[u8]) -> Result<Header> {
        let le = i32::from_le_bytes(h[0..4].try_into().unwrap());
        let be = i32::from_be_bytes(h[0..4].try_into().unwrap());
        let big_endian = match (le, be) {
            (348, _) => false,
            (_, 348) => true,
            (540, _) | (_, 540) => bail!("NIfTI-2 files are not supported (only NIfTI-1)"),
            _ => bail!("not a NIfTI-1 file (sizeof_hdr is {le}, expected 348)"),
        };
        let magic = &h[344..348];
        match magic {
            b"n+1\0" => {}
            b"ni1\0" => bail!(
                "magic 'ni1' (a .hdr/.img pair) is not supported: only single .nii files \
                 (magic 'n+1')"
            ),
            _ => bail!(
                "bad magic {:?}, expected \"n+1\\0\" (not a NIfTI-1 file?)",
                String::from_utf8_lossy(magic)
            ),
        }
        let i16_at = |o: usize| {
            let b = [h[o], h[o + 1]];
            if big_endian {
                i16::from_be_bytes(b)
            } else {
                i16::from_le_bytes(b)
            }
        };
        let f32_at = |o: usize| {
            let b: [u8; 4] = h[o..o + 4].try_into().unwrap();
            if big_endian {
                f32::from_be_bytes(b)
            } else {
                f32::from_le_bytes(b)
            }
        };
        let dim: Vec<i16> = (0..8).map(|i| i16_at(40 + 2 * i)).collect();
        let ndim = dim[0];
        ensure!(
            (1..=7).contains(&ndim),
            "dim[0] = {ndim} is not a number of dimensions (1 to 7)"
        );
        let ndim = ndim as usize;
        let d = |i: usize| if i <= ndim { dim[i] as i64 } else { 1 };
        for (i, &n) in dim.iter().enumerate().take(ndim + 1).skip(4) {
            ensure!(
                n == 1,
                "{ndim}-D data with dim[{i}] = {n} is not supported (only 3-D volumes)"
            );
        }
        let dims = checked_dims([d(1), d(2), d(3)])?;
        let datatype = i16_at(70);
        let bitpix = i16_at(72);
        let sample = match datatype {
            2 => Sample::U8,
            4 => Sample::I16,
            8 => Sample::I32,
            16 => Sample::F32,
            64 => Sample::F64,
            256 => Sample::I8,
            512 => Sample::U16,
            768 => Sample::U32,
            other => bail!(
                "unsupported datatype {other} (supported: uint8, int8, int16, uint16, int32, \
                 uint32, float32, float64)"
            ),
        };
        ensure!(
            bitpix as usize == sample.size() * 8,
            "bitpix {bitpix} does not match datatype {datatype} ({})",
            sample.name()
        );
        let pd = |i: usize| f32_at(76 + 4 * i) as f64;
        let pixdim = [pd(1), pd(2), pd(3)];
        let vox_offset = f32_at(108);
        ensure!(
            vox_offset.is_finite()
                && vox_offset >= HEADER as f32
                && vox_offset.fract() == 0.0
                && vox_offset < 1e9,
            "bad vox_offset {vox_offset} (must be a whole number of bytes, at least {HEADER})"
        );
        let slope = f32_at(112) as f64;
        let inter = f32_at(116) as f64;
        // The standard: a zero scl_slope means the data are not scaled.
        let rescale = if slope == 0.0 || !slope.is_finite() {
            None
        } else {
            ensure!(inter.is_finite(), "scl_inter {inter} is not finite");
            Rescale::non_identity(slope, inter)
        };
        let axes = orientation(i16_at(252), i16_at(254), &f32_at);
        Ok(Header {
            axes,
            big_endian,
            dims,
            sample,
            pixdim,
            vox_offset: vox_offset as usize,
            rescale,
        })
    }

    fn data_end(&self, opts: &LoadOptions) -> Result<usize> {
        header_bytes(self.dims, self.sample, opts)?
            .checked_add(self.vox_offset)
            .ok_or_else(|| anyhow!("vox_offset + data size overflows"))
    }
}

/// The voxel axes' directions in the patient's LPS frame from a NIfTI-1 header: the sform
/// when `sform_code` > 0, else the qform (quaternion, qfac = pixdim[0]) when
/// `qform_code` > 0, else `None`. NIfTI's world is RAS, so x and y are negated.
fn orientation(
    qform_code: i16,
    sform_code: i16,
    f32_at: &dyn Fn(usize) -> f32,
) -> Option<[[f32; 3]; 3]> {
    // m[row][col]: column c is voxel axis c in RAS (scaled by the voxel size).
    let m: [[f64; 3]; 3] = if sform_code > 0 {
        std::array::from_fn(|r| std::array::from_fn(|c| f32_at(280 + 16 * r + 4 * c) as f64))
    } else if qform_code > 0 {
        let (b, c, d) = (f32_at(256) as f64, f32_at(260) as f64, f32_at(264) as f64);
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let qfac = if f32_at(76) < 0.0 { -1.0 } else { 1.0 };
        [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (b * d + a * c) * qfac,
            ],
            [
                2.0 * (b * c + a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d - a * b) * qfac,
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (c * d + a * b),
                (a * a + d * d - c * c - b * b) * qfac,
            ],
        ]
    } else {
        return None;
    };
    let axis = |c: usize| {
        let v = [-m[0][c], -m[1][c], m[2][c]]; // RAS -> LPS
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (l.is_finite() && l > 0.0).then(|| v.map(|x| (x / l) as f32))
    };
    Some([axis(0)?, axis(1)?, axis(2)?])
}

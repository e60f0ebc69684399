//! The small sample volumes (5 × 4 × 3 voxels of every sample type) and header builders
//! the format tests and the fuzz harness's seeds share. Included with `#[path]` by
//! tests/formats.rs and tests/fuzz/seeds.rs (not a module of tests/common).
#![allow(dead_code)]

use base64::Engine as _;

pub const DIMS: [u32; 3] = [5, 4, 3];
pub const N: usize = 60;

pub fn u8s() -> Vec<u8> {
    (0..N).map(|i| (i * 7 % 256) as u8).collect()
}

pub fn u16s() -> Vec<u16> {
    (0..N).map(|i| (i * 1009 % 65536) as u16).collect()
}

pub fn i16s() -> Vec<i16> {
    (0..N)
        .map(|i| (i as i32 * 997 % 4000 - 2000) as i16)
        .collect()
}

pub fn f32s() -> Vec<f32> {
    (0..N).map(|i| i as f32 * 0.25 - 3.0).collect()
}

pub fn le16(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

pub fn be16(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

pub fn le_u16(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

pub fn be_u16(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

pub fn le_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

pub fn b64(data: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(data)
}

pub fn mhd(fields: &str, edf: &str) -> String {
    format!("ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\n{fields}ElementDataFile = {edf}\n")
}

/// A NIfTI-1 header; `vox_offset` ≥ 352 leaves room for the 4 extension bytes.
#[allow(clippy::too_many_arguments)]
pub fn nifti_header(
    dims: &[i16],
    datatype: i16,
    bitpix: i16,
    pixdim: [f32; 3],
    vox_offset: f32,
    slope: f32,
    inter: f32,
    be: bool,
) -> Vec<u8> {
    let mut h = vec![0u8; vox_offset as usize];
    let p16 = |h: &mut Vec<u8>, o: usize, v: i16| {
        h[o..o + 2].copy_from_slice(&if be { v.to_be_bytes() } else { v.to_le_bytes() })
    };
    let p32 = |h: &mut Vec<u8>, o: usize, v: [u8; 4], r: [u8; 4]| {
        h[o..o + 4].copy_from_slice(if be { &r } else { &v })
    };
    p32(&mut h, 0, 348i32.to_le_bytes(), 348i32.to_be_bytes());
    p16(&mut h, 40, dims.len() as i16);
    for (i, &d) in dims.iter().enumerate() {
        p16(&mut h, 42 + 2 * i, d);
    }
    p16(&mut h, 70, datatype);
    p16(&mut h, 72, bitpix);
    let f = |h: &mut Vec<u8>, o: usize, v: f32| p32(h, o, v.to_le_bytes(), v.to_be_bytes());
    f(&mut h, 76, 1.0);
    for (i, &d) in pixdim.iter().enumerate() {
        f(&mut h, 80 + 4 * i, d);
    }
    f(&mut h, 108, vox_offset);
    f(&mut h, 112, slope);
    f(&mut h, 116, inter);
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

/// A small scene file: a procedural sphere, inline transfer functions, a flat background.
pub const SMALL: &str = r#"
name = "tiny"
[volume]
builtin = "sphere"
size = 24
[transfer]
colour = [[0.0, 1.0, 0.0, 0.0]]
opacity = [[0.0, 0.0], [0.5, 0.0], [0.6, 1.0], [1.0, 1.0]]
[camera]
eye = [0.0, 0.0, 2.5]
fov = 30
[environment]
map = "none"
[render]
width = 24
height = 20
background = [0.0, 0.0, 1.0, 1.0]
tonemap = "none"
reflections = false
"#;

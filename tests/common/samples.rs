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

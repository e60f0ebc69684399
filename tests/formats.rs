//! Issue 6: volume file loaders. Every file here is built byte by byte by the test itself
//! (headers as strings, data with flate2/base64 directly), loaded with `load_volume`, and
//! checked against the array it was made from; every bad input must give a one-line error
//! naming the file and the reason.
//!
//! The `real_*` tests load the files `scripts/fetch-data` puts in `$REFRAKT_DATA_DIR`
//! (default `~/.cache/refrakt/data`). A missing file skips the test (with a line saying so)
//! unless `REFRAKT_REQUIRE_DATA` is set (to anything but `0`), which makes it a failure.

use std::io::Write;
use std::path::{Path, PathBuf};

use flate2::write::{GzEncoder, ZlibEncoder};
use flate2::Compression;
use refrakt::volume::formats::{
    check_limits, is_volume_file, load_volume, LoadOptions, RawLayout, ScalarKind,
};
use refrakt::volume::{Volume, Voxels};

#[path = "common/samples.rs"]
mod samples;
use samples::*;

fn as_f32<T: Copy + Into<f64>>(v: &[T]) -> Vec<f32> {
    v.iter().map(|&x| x.into() as f32).collect()
}

fn gzip(data: &[u8]) -> Vec<u8> {
    let mut e = GzEncoder::new(Vec::new(), Compression::default());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}
fn zlib(data: &[u8]) -> Vec<u8> {
    let mut e = ZlibEncoder::new(Vec::new(), Compression::default());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn load(path: &Path) -> Volume {
    load_opts(path, &LoadOptions::default())
}
fn load_opts(path: &Path, opts: &LoadOptions) -> Volume {
    load_volume(path, opts).unwrap_or_else(|e| panic!("{e}"))
}

/// Loading must fail with one line naming the file and containing every keyword.
#[track_caller]
fn expect_err(path: &Path, keywords: &[&str]) -> String {
    expect_err_opts(path, &LoadOptions::default(), keywords)
}
#[track_caller]
fn expect_err_opts(path: &Path, opts: &LoadOptions, keywords: &[&str]) -> String {
    let msg = match load_volume(path, opts) {
        Ok(v) => panic!(
            "{} loaded ({:?}), expected an error",
            path.display(),
            v.dims
        ),
        Err(e) => e.to_string(),
    };
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*name), "error does not name '{name}': {msg}");
    assert!(!msg.contains('\n'), "error is not one line: {msg}");
    for k in keywords {
        assert!(msg.contains(k), "error lacks '{k}': {msg}");
    }
    msg
}

#[track_caller]
fn assert_f32(v: &Volume, expected: &[f32], spacing: [f32; 3]) {
    assert_eq!(v.dims, DIMS);
    assert_eq!(v.spacing, spacing);
    assert_eq!(v.voxels, Voxels::F32(expected.to_vec()));
}

// ---------------------------------------------------------------------------------------
// raw

#[test]
fn raw_explicit_layout_every_kind() {
    let dir = tempfile::tempdir().unwrap();
    let layout = |kind| LoadOptions {
        raw: Some(RawLayout {
            dims: DIMS,
            kind,
            spacing: Some([1.0, 2.0, 3.0]),
        }),
        ..Default::default()
    };
    let p = write(dir.path(), "a.bin", &u8s());
    let v = load_opts(&p, &layout(ScalarKind::U8));
    assert_eq!(v.voxels, Voxels::U8(u8s()));
    assert_eq!(v.spacing, [1.0, 2.0, 3.0]);
    assert_eq!(v.range, None);

    let p = write(dir.path(), "b.dat", &le_u16(&u16s()));
    assert_eq!(
        load_opts(&p, &layout(ScalarKind::U16)).voxels,
        Voxels::U16(u16s())
    );

    let p = write(dir.path(), "c", &le16(&i16s()));
    assert_f32(
        &load_opts(&p, &layout(ScalarKind::I16)),
        &as_f32(&i16s()),
        [1.0, 2.0, 3.0],
    );

    let p = write(dir.path(), "d.raw", &le_f32(&f32s()));
    let mut opts = layout(ScalarKind::F32);
    opts.spacing = Some([0.5, 0.5, 0.5]);
    opts.window = Some((-1.0, 1.0));
    let v = load_opts(&p, &opts);
    assert_f32(&v, &f32s(), [0.5, 0.5, 0.5]);
    assert_eq!(v.range, Some((-1.0, 1.0)));
}

#[test]
fn raw_open_scivis_name_gives_the_layout() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "tiny_5x4x3_int16.raw", &le16(&i16s()));
    assert!(is_volume_file(&p));
    assert_f32(&load(&p), &as_f32(&i16s()), [1.0; 3]);
    let p = write(dir.path(), "tiny_5x4x3_uint16.raw", &le_u16(&u16s()));
    assert_eq!(load(&p).voxels, Voxels::U16(u16s()));
    let p = write(dir.path(), "my_vol_5x4x3_uint8.raw", &u8s());
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));
    // A window turns u8 data into f32 with that range.
    let v = load_opts(
        &p,
        &LoadOptions {
            window: Some((0.0, 100.0)),
            ..Default::default()
        },
    );
    assert_eq!(v.voxels, Voxels::F32(as_f32(&u8s())));
    assert_eq!(v.range, Some((0.0, 100.0)));
}

#[test]
fn raw_errors_name_file_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    // dims × type ≠ file size: both sizes in the message.
    let p = write(dir.path(), "short_5x4x3_int16.raw", &le16(&i16s())[..100]);
    expect_err(&p, &["100 bytes", "120 bytes"]);
    let p = write(dir.path(), "long_5x4x3_uint8.raw", &[0; 61]);
    expect_err(&p, &["61 bytes", "60 bytes"]);
    let p = write(dir.path(), "x_5x4x3_float64.raw", &[0; 480]);
    expect_err(&p, &["float64", "not supported"]);
    let p = write(dir.path(), "noname.raw", &[0; 60]);
    expect_err(&p, &["layout is unknown"]);
    let p = write(dir.path(), "zero_5x0x3_uint8.raw", &[]);
    expect_err(&p, &["non-positive"]);
    let opts = LoadOptions {
        raw: Some(RawLayout {
            dims: [5, 0, 3],
            kind: ScalarKind::U8,
            spacing: None,
        }),
        ..Default::default()
    };
    expect_err_opts(&p, &opts, &["non-positive"]);
    // Huge dims: no overflow, no allocation, just an error.
    let opts = LoadOptions {
        raw: Some(RawLayout {
            dims: [u32::MAX; 3],
            kind: ScalarKind::F32,
            spacing: None,
        }),
        ..Default::default()
    };
    expect_err_opts(&p, &opts, &["overflow"]);
    let missing = dir.path().join("gone_5x4x3_uint8.raw");
    expect_err(&missing, &["cannot read"]);
    let p = write(dir.path(), "scene.toml", b"x = 1");
    expect_err(&p, &["unknown volume format"]);
    // Bad options are errors too.
    let p = write(dir.path(), "ok_5x4x3_uint8.raw", &u8s());
    let opts = LoadOptions {
        window: Some((5.0, 5.0)),
        ..Default::default()
    };
    expect_err_opts(&p, &opts, &["window"]);
}

// ---------------------------------------------------------------------------------------
// NRRD

fn nrrd(fields: &str, data: &[u8]) -> Vec<u8> {
    let mut f =
        format!("NRRD0004\n# Complete NRRD file format specification at:\n{fields}\n").into_bytes();
    f.extend_from_slice(data);
    f
}

#[test]
fn nrrd_attached_raw_and_gzip() {
    let dir = tempfile::tempdir().unwrap();
    let h = "type: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 5 4 3\n\
             space directions: (0.5,0,0) (0,0.75,0) (0,0,2.5)\nkinds: domain domain domain\n\
             endian: little\nencoding: raw\nspace origin: (1,2,3)\n";
    let p = write(dir.path(), "a.nrrd", &nrrd(h, &le16(&i16s())));
    assert_f32(&load(&p), &as_f32(&i16s()), [0.5, 0.75, 2.5]);

    let h = "type: ushort\ndimension: 3\nsizes: 5 4 3\nspacings: 1 2 3\nendian: big\n\
             encoding: gzip\nmeta:=data\n";
    let p = write(dir.path(), "b.nrrd", &nrrd(h, &gzip(&be_u16(&u16s()))));
    let v = load(&p);
    assert_eq!(v.voxels, Voxels::U16(u16s()));
    assert_eq!(v.spacing, [1.0, 2.0, 3.0]);

    let h = "type: float\ndimension: 3\nsizes: 5 4 3\nendian: little\nencoding: gz\n";
    let p = write(dir.path(), "c.nrrd", &nrrd(h, &gzip(&le_f32(&f32s()))));
    assert_f32(&load(&p), &f32s(), [1.0; 3]);

    let h = "type: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: ascii\n";
    let text: Vec<String> = u8s().iter().map(|x| x.to_string()).collect();
    let p = write(dir.path(), "d.nrrd", &nrrd(h, text.join(" ").as_bytes()));
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));

    // int and double become f32.
    let ints: Vec<i32> = (0..N as i32).map(|i| i * 1000 - 7).collect();
    let h = "type: int32\ndimension: 3\nsizes: 5 4 3\nendian: little\nencoding: raw\n";
    let data: Vec<u8> = ints.iter().flat_map(|x| x.to_le_bytes()).collect();
    let p = write(dir.path(), "e.nrrd", &nrrd(h, &data));
    assert_f32(&load(&p), &as_f32(&ints), [1.0; 3]);
    let dbl: Vec<f64> = (0..N).map(|i| i as f64 / 8.0).collect();
    let h = "type: double\ndimension: 3\nsizes: 5 4 3\nendian: big\nencoding: raw\n";
    let data: Vec<u8> = dbl.iter().flat_map(|x| x.to_be_bytes()).collect();
    let p = write(dir.path(), "f.nrrd", &nrrd(h, &data));
    assert_f32(&load(&p), &as_f32(&dbl), [1.0; 3]);

    // CRLF line endings.
    let h = "type: uint8\r\ndimension: 3\r\nsizes: 5 4 3\r\nencoding: raw\r\n";
    let mut f = format!("NRRD0004\r\n{h}\r\n").into_bytes();
    f.extend_from_slice(&u8s());
    let p = write(dir.path(), "g.nrrd", &f);
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));
}

#[test]
fn nrrd_detached_header_and_skips() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "vol.raw", &le16(&i16s()));
    let h = "NRRD0005\ntype: int16\ndimension: 3\nsizes: 5 4 3\nendian: little\n\
             encoding: raw\ndata file: vol.raw\n";
    let p = write(dir.path(), "a.nhdr", h.as_bytes());
    assert!(is_volume_file(&p));
    assert_f32(&load(&p), &as_f32(&i16s()), [1.0; 3]);

    // Gzip'd data file with a line skip before the stream and a byte skip inside it.
    let mut data = b"a comment line\n".to_vec();
    data.extend(gzip(&[&[9u8; 7][..], &u8s()].concat()));
    write(dir.path(), "vol.raw.gz", &data);
    let h = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: gzip\n\
             line skip: 1\nbyte skip: 7\ndatafile: vol.raw.gz\n\n";
    let p = write(dir.path(), "b.nhdr", h.as_bytes());
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));

    // byte skip -1: the data is at the end of the file.
    write(dir.path(), "tail.bin", &[&[1u8; 33][..], &u8s()].concat());
    let h = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: raw\n\
             byte skip: -1\ndata file: tail.bin\n";
    let p = write(dir.path(), "c.nhdr", h.as_bytes());
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));

    // Spacing option overrides the header.
    let opts = LoadOptions {
        spacing: Some([3.0, 2.0, 1.0]),
        ..Default::default()
    };
    assert_eq!(load_opts(&p, &opts).spacing, [3.0, 2.0, 1.0]);
}

#[test]
fn nrrd_errors_name_file_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let base = "type: short\ndimension: 3\nsizes: 5 4 3\nendian: little\n";
    let raw = le16(&i16s());

    let p = write(
        dir.path(),
        "short.nrrd",
        &nrrd(&format!("{base}encoding: raw\n"), &raw[..99]),
    );
    expect_err(&p, &["99 bytes", "120 bytes", "too short"]);
    let p = write(
        dir.path(),
        "long.nrrd",
        &nrrd(
            &format!("{base}encoding: raw\n"),
            &[&raw[..], &[0, 0]].concat(),
        ),
    );
    expect_err(&p, &["122 bytes", "120 bytes", "too long"]);
    let p = write(
        dir.path(),
        "bz.nrrd",
        &nrrd(&format!("{base}encoding: bzip2\n"), &raw),
    );
    expect_err(&p, &["unsupported encoding 'bzip2'"]);
    let p = write(
        dir.path(),
        "i64.nrrd",
        &nrrd(
            "type: int64\ndimension: 3\nsizes: 5 4 3\nendian: little\nencoding: raw\n",
            &[0; 480],
        ),
    );
    expect_err(&p, &["unsupported type 'int64'"]);
    let mut bad = gzip(&raw);
    let mid = bad.len() / 2;
    bad[mid] ^= 0xff;
    bad[mid + 1] ^= 0x55;
    let p = write(
        dir.path(),
        "corrupt.nrrd",
        &nrrd(&format!("{base}encoding: gzip\n"), &bad),
    );
    expect_err(&p, &["gzip"]);
    let trunc = gzip(&raw);
    let p = write(
        dir.path(),
        "truncgz.nrrd",
        &nrrd(
            &format!("{base}encoding: gzip\n"),
            &trunc[..trunc.len() / 2],
        ),
    );
    expect_err(&p, &["gzip"]);
    let p = write(
        dir.path(),
        "zero.nrrd",
        &nrrd(
            "type: uchar\ndimension: 3\nsizes: 5 0 3\nencoding: raw\n",
            &[],
        ),
    );
    expect_err(&p, &["non-positive"]);
    let p = write(
        dir.path(),
        "huge.nrrd",
        &nrrd(
            "type: double\ndimension: 3\nsizes: 4294967295 4294967295 4294967295\n\
             endian: little\nencoding: gzip\n",
            &gzip(&[0; 64]),
        ),
    );
    expect_err(&p, &["overflow"]);
    let p = write(
        dir.path(),
        "huge2.nrrd",
        &nrrd(
            "type: uchar\ndimension: 3\nsizes: 100000 100000 100\nencoding: gzip\n",
            &gzip(&[0; 64]),
        ),
    );
    expect_err(&p, &["gzip", "64 bytes", "1000000000000 bytes"]);
    let p = write(dir.path(), "trunc.nrrd", b"NRRD0004\ntype: short\ndimen");
    expect_err(&p, &["truncated"]);
    let p = write(dir.path(), "nomagic.nrrd", b"P5\n5 4\n255\n");
    expect_err(&p, &["not an NRRD file"]);
    let p = write(
        dir.path(),
        "missing.nhdr",
        format!("NRRD0004\n{base}encoding: raw\ndata file: nowhere.raw\n").as_bytes(),
    );
    expect_err(&p, &["nowhere.raw", "cannot read"]);
    write(dir.path(), "half.raw", &raw[..60]);
    let p = write(
        dir.path(),
        "half.nhdr",
        format!("NRRD0004\n{base}encoding: raw\ndata file: half.raw\n").as_bytes(),
    );
    expect_err(&p, &["half.raw", "60 bytes", "120 bytes"]);
    let p = write(
        dir.path(),
        "noendian.nrrd",
        &nrrd(
            "type: short\ndimension: 3\nsizes: 5 4 3\nencoding: raw\n",
            &raw,
        ),
    );
    expect_err(&p, &["endian"]);
    let p = write(
        dir.path(),
        "twod.nrrd",
        &nrrd(
            "type: uchar\ndimension: 2\nsizes: 5 4\nencoding: raw\n",
            &[0; 20],
        ),
    );
    expect_err(&p, &["dimension 2"]);
}

// ---------------------------------------------------------------------------------------
// NIfTI-1

#[test]
fn nifti_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let d = [5, 4, 3];
    let nii = |h: Vec<u8>, data: &[u8]| [h, data.to_vec()].concat();

    let p = write(
        dir.path(),
        "a.nii",
        &nii(
            nifti_header(&d, 2, 8, [0.9, 1.1, 2.0], 352.0, 0.0, 0.0, false),
            &u8s(),
        ),
    );
    let v = load(&p);
    assert_eq!(v.voxels, Voxels::U8(u8s()));
    assert_eq!(v.spacing, [0.9, 1.1, 2.0]);

    // scl_slope / scl_inter applied: u16 becomes f32.
    let p = write(
        dir.path(),
        "b.nii",
        &nii(
            nifti_header(&d, 512, 16, [1.0; 3], 352.0, 2.0, -5.0, false),
            &le_u16(&u16s()),
        ),
    );
    let want: Vec<f32> = u16s().iter().map(|&x| x as f32 * 2.0 - 5.0).collect();
    assert_f32(&load(&p), &want, [1.0; 3]);
    // slope 1, inter 0: no scaling, u16 stays u16.
    let p = write(
        dir.path(),
        "c.nii",
        &nii(
            nifti_header(&d, 512, 16, [1.0; 3], 352.0, 1.0, 0.0, false),
            &le_u16(&u16s()),
        ),
    );
    assert_eq!(load(&p).voxels, Voxels::U16(u16s()));

    // int16, big-endian, 4-D with one time point, vox_offset past an extension.
    let p = write(
        dir.path(),
        "d.nii",
        &nii(
            nifti_header(&[5, 4, 3, 1], 4, 16, [1.0; 3], 400.0, 0.0, 0.0, true),
            &be16(&i16s()),
        ),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), [1.0; 3]);

    // float32 gzip'd.
    let f = nii(
        nifti_header(&d, 16, 32, [2.0; 3], 352.0, 0.0, 0.0, false),
        &le_f32(&f32s()),
    );
    let p = write(dir.path(), "e.nii.gz", &gzip(&f));
    assert!(is_volume_file(&p));
    assert_f32(&load(&p), &f32s(), [2.0; 3]);

    // int32 and float64 become f32.
    let ints: Vec<i32> = (0..N as i32).map(|i| 100_000 - i * 3).collect();
    let data: Vec<u8> = ints.iter().flat_map(|x| x.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "f.nii",
        &nii(
            nifti_header(&d, 8, 32, [1.0; 3], 352.0, 0.0, 0.0, false),
            &data,
        ),
    );
    assert_f32(&load(&p), &as_f32(&ints), [1.0; 3]);
    let dbl: Vec<f64> = (0..N).map(|i| -(i as f64) / 4.0).collect();
    let data: Vec<u8> = dbl.iter().flat_map(|x| x.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "g.nii.gz",
        &gzip(&nii(
            nifti_header(&d, 64, 64, [1.0; 3], 352.0, 0.0, 0.0, false),
            &data,
        )),
    );
    assert_f32(&load(&p), &as_f32(&dbl), [1.0; 3]);
}

#[test]
fn nifti_errors_name_file_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = [5, 4, 3];
    let good = [
        nifti_header(&d, 4, 16, [1.0; 3], 352.0, 0.0, 0.0, false),
        le16(&i16s()),
    ]
    .concat();

    let mut bad = good.clone();
    bad[344..348].copy_from_slice(b"abc\0");
    let p = write(dir.path(), "magic.nii", &bad);
    expect_err(&p, &["bad magic"]);
    let mut pair = good.clone();
    pair[344..348].copy_from_slice(b"ni1\0");
    let p = write(dir.path(), "pair.nii", &pair);
    expect_err(&p, &["magic 'ni1'", "not supported"]);
    let p = write(dir.path(), "trunc.nii", &good[..200]);
    expect_err(&p, &["truncated header", "200 bytes"]);
    let p = write(dir.path(), "trunc.nii.gz", &gzip(&good[..200]));
    expect_err(&p, &["truncated header", "200 bytes"]);
    let p = write(dir.path(), "short.nii", &good[..good.len() - 10]);
    expect_err(&p, &["462 bytes", "472 bytes", "too short"]);
    let p = write(dir.path(), "long.nii", &[&good[..], &[0; 3]].concat());
    expect_err(&p, &["475 bytes", "472 bytes", "too long"]);
    let p = write(dir.path(), "short.nii.gz", &gzip(&good[..good.len() - 10]));
    expect_err(&p, &["462 bytes", "472 bytes"]);
    let p = write(
        dir.path(),
        "long.nii.gz",
        &gzip(&[&good[..], &[0; 3]].concat()),
    );
    expect_err(&p, &["472 bytes", "too long"]);
    let mut gz = gzip(&good);
    let n = gz.len();
    gz[n - 12] ^= 0xff; // inside the deflate stream or its CRC
    gz[n - 5] ^= 0xff; // the length/CRC trailer
    let p = write(dir.path(), "corrupt.nii.gz", &gz);
    expect_err(&p, &["gzip", "corrupt"]);
    let p = write(
        dir.path(),
        "zero.nii",
        &nifti_header(&[5, 0, 3], 2, 8, [1.0; 3], 352.0, 0.0, 0.0, false),
    );
    expect_err(&p, &["non-positive"]);
    let p = write(
        dir.path(),
        "neg.nii",
        &nifti_header(&[5, -4, 3], 2, 8, [1.0; 3], 352.0, 0.0, 0.0, false),
    );
    expect_err(&p, &["non-positive"]);
    let p = write(
        dir.path(),
        "complex.nii",
        &nifti_header(&d, 32, 64, [1.0; 3], 352.0, 0.0, 0.0, false),
    );
    expect_err(&p, &["unsupported datatype 32"]);
    let p = write(
        dir.path(),
        "time.nii",
        &nifti_header(&[5, 4, 3, 2], 2, 8, [1.0; 3], 352.0, 0.0, 0.0, false),
    );
    expect_err(&p, &["dim[4] = 2", "not supported"]);
    let p = write(
        dir.path(),
        "offset.nii",
        &nifti_header(&d, 2, 8, [1.0; 3], 352.0, 0.0, 0.0, false)
            .into_iter()
            .enumerate()
            .map(|(i, b)| if (108..112).contains(&i) { 0x7f } else { b })
            .collect::<Vec<_>>(),
    );
    expect_err(&p, &["vox_offset"]);
    let p = write(
        dir.path(),
        "pixdim.nii",
        &[
            nifti_header(&d, 2, 8, [1.0, 0.0, 1.0], 352.0, 0.0, 0.0, false),
            u8s(),
        ]
        .concat(),
    );
    expect_err(&p, &["spacing"]);
    // ... which a spacing option fixes.
    let opts = LoadOptions {
        spacing: Some([1.0; 3]),
        ..Default::default()
    };
    assert_eq!(load_opts(&p, &opts).voxels, Voxels::U8(u8s()));
}

/// Headers that contradict themselves are refused, not read with one of the two winning:
/// a field given twice (the last won), NRRD's `spacings` beside `space directions` (the
/// spacings were dropped), a MetaImage line after an external ElementDataFile (ignored).
#[test]
fn contradictory_headers_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let raw = le16(&i16s());
    let base = "type: short\ndimension: 3\nsizes: 5 4 3\nendian: little\nencoding: raw\n";
    let p = write(
        dir.path(),
        "twice.nrrd",
        &nrrd(&format!("{base}type: float\n"), &raw),
    );
    expect_err(&p, &["twice.nrrd", "'type' is given twice"]);
    let p = write(
        dir.path(),
        "both.nrrd",
        &nrrd(
            &format!(
                "{base}spacings: 5 5 5\nspace: left-posterior-superior\n\
                 space directions: (1,0,0) (0,1,0) (0,0,1)\n"
            ),
            &raw,
        ),
    );
    expect_err(&p, &["both.nrrd", "'space directions' and 'spacings'"]);
    let p = write(
        dir.path(),
        "twice.mha",
        &[
            mhd("DimSize = 5 4 2\nElementType = MET_SHORT\n", "LOCAL").as_bytes(),
            &raw[..],
        ]
        .concat(),
    );
    expect_err(&p, &["twice.mha", "'DimSize' is given twice"]);
    write(dir.path(), "after.raw", &raw);
    let p = write(
        dir.path(),
        "after.mhd",
        format!(
            "{}ElementSpacing = 2 2 2\n",
            mhd("ElementType = MET_SHORT\n", "after.raw")
        )
        .as_bytes(),
    );
    expect_err(
        &p,
        &["after.mhd", "after ElementDataFile", "ElementSpacing"],
    );
}

// ---------------------------------------------------------------------------------------
// MetaImage

#[test]
fn metaimage_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let f = mhd(
        "BinaryData = True\nBinaryDataByteOrderMSB = False\nElementSpacing = 0.5 0.5 2\n\
         ElementType = MET_SHORT\n",
        "LOCAL",
    );
    let p = write(
        dir.path(),
        "a.mha",
        &[f.as_bytes(), &le16(&i16s())].concat(),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), [0.5, 0.5, 2.0]);

    let z = zlib(&le_f32(&f32s()));
    let f = mhd(
        &format!(
            "BinaryData = True\nCompressedData = True\nCompressedDataSize = {}\n\
             ElementType = MET_FLOAT\n",
            z.len()
        ),
        "LOCAL",
    );
    let p = write(dir.path(), "b.mha", &[f.as_bytes(), &z].concat());
    assert_f32(&load(&p), &f32s(), [1.0; 3]);
    // A stale CompressedDataSize (VTK's frogtissue.mhd states 260020 bytes of its 262087)
    // over a whole stream of the right size loads (with a warning); a cut stream whose
    // length disagrees with the header is refused, naming both sizes.
    let stale = f.replace(
        &format!("CompressedDataSize = {}", z.len()),
        &format!("CompressedDataSize = {}", z.len() - 7),
    );
    let p = write(dir.path(), "b2.mha", &[stale.as_bytes(), &z].concat());
    assert_f32(&load(&p), &f32s(), [1.0; 3]);
    let p = write(
        dir.path(),
        "b3.mha",
        &[f.as_bytes(), &z[..z.len() - 7]].concat(),
    );
    expect_err(
        &p,
        &[
            &format!("{} bytes", z.len() - 7),
            "CompressedDataSize",
            "zlib",
        ],
    );

    write(dir.path(), "c.raw", &be_u16(&u16s()));
    let f = mhd(
        "BinaryData = True\nBinaryDataByteOrderMSB = True\nElementSize = 1 2 3\n\
         ElementType = MET_USHORT\n",
        "c.raw",
    );
    let p = write(dir.path(), "c.mhd", f.as_bytes());
    let v = load(&p);
    assert_eq!(v.voxels, Voxels::U16(u16s()));
    assert_eq!(v.spacing, [1.0, 2.0, 3.0]);

    write(dir.path(), "d.zraw", &zlib(&u8s()));
    let f = mhd(
        "CompressedData = True\nElementSpacing = 1 1 1\nElementType = MET_UCHAR\n",
        "d.zraw",
    );
    let p = write(dir.path(), "d.mhd", f.as_bytes());
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));

    // CRLF header, HeaderSize skip in the data file.
    write(
        dir.path(),
        "e.raw",
        &[&[0u8; 16][..], &le16(&i16s())].concat(),
    );
    let f = mhd("HeaderSize = 16\nElementType = MET_SHORT\n", "e.raw").replace('\n', "\r\n");
    let p = write(dir.path(), "e.mhd", f.as_bytes());
    assert_f32(&load(&p), &as_f32(&i16s()), [1.0; 3]);
}

#[test]
fn metaimage_errors_name_file_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let f = mhd("ElementType = MET_SHORT\n", "LOCAL");
    let p = write(
        dir.path(),
        "short.mha",
        &[f.as_bytes(), &le16(&i16s())[..50]].concat(),
    );
    expect_err(&p, &["50 bytes", "120 bytes"]);
    write(dir.path(), "long.raw", &[0u8; 130]);
    let p = write(
        dir.path(),
        "long.mhd",
        mhd("ElementType = MET_SHORT\n", "long.raw").as_bytes(),
    );
    expect_err(&p, &["long.raw", "130 bytes", "120 bytes"]);
    let mut z = zlib(&le16(&i16s()));
    let n = z.len();
    z[n / 2] ^= 0xff;
    z[n - 2] ^= 0xff;
    let f = mhd("CompressedData = True\nElementType = MET_SHORT\n", "LOCAL");
    let p = write(dir.path(), "corrupt.mha", &[f.as_bytes(), &z].concat());
    expect_err(&p, &["zlib"]);
    let z = zlib(&le16(&i16s()));
    let p = write(
        dir.path(),
        "trunc.mha",
        &[f.as_bytes(), &z[..z.len() / 2]].concat(),
    );
    expect_err(&p, &["zlib", "truncated"]);
    let f = mhd("ElementType = MET_LONG_LONG\n", "LOCAL");
    let p = write(dir.path(), "type.mha", f.as_bytes());
    expect_err(&p, &["unsupported ElementType 'MET_LONG_LONG'"]);
    let f = mhd("ElementType = MET_UCHAR\n", "gone.raw");
    let p = write(dir.path(), "gone.mhd", f.as_bytes());
    expect_err(&p, &["gone.raw", "cannot read"]);
    let p = write(dir.path(), "nodata.mha", b"ObjectType = Image\nNDims = 3\n");
    expect_err(&p, &["ElementDataFile", "truncated"]);
    let f = "NDims = 3\nDimSize = 5 -4 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    let p = write(dir.path(), "neg.mha", f.as_bytes());
    expect_err(&p, &["non-positive"]);
    let f = mhd("ElementType = MET_UCHAR\n", "LIST");
    let p = write(dir.path(), "list.mhd", f.as_bytes());
    expect_err(&p, &["LIST", "not supported"]);
}

// ---------------------------------------------------------------------------------------
// VTK XML ImageData

fn vti(vtkfile_attrs: &str, array: &str, appended: Option<(&str, &[u8])>) -> Vec<u8> {
    let mut f = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" {vtkfile_attrs}>\n  \
         <ImageData WholeExtent=\"0 4 10 13 -1 1\" Origin=\"0 0 0\" Spacing=\"0.5 1 2\">\n    \
         <Piece Extent=\"0 4 10 13 -1 1\">\n      <PointData Scalars=\"density\">\n        \
         {array}\n      </PointData>\n      <CellData>\n      </CellData>\n    </Piece>\n  \
         </ImageData>\n"
    )
    .into_bytes();
    if let Some((enc, data)) = appended {
        f.extend(format!("  <AppendedData encoding=\"{enc}\">\n   _").bytes());
        f.extend_from_slice(data);
        f.extend(b"\n  </AppendedData>\n");
    }
    f.extend(b"</VTKFile>\n");
    f
}

/// VTK's zlib block layout: header [nblocks, block size, last size, sizes…] + blocks.
fn vtk_zlib(data: &[u8], block: usize, word8: bool, be: bool) -> (Vec<u8>, Vec<u8>) {
    let blocks: Vec<Vec<u8>> = data.chunks(block).map(zlib).collect();
    let last = data.len() % block;
    let mut words = vec![blocks.len() as u64, block as u64, last as u64];
    words.extend(blocks.iter().map(|b| b.len() as u64));
    let header: Vec<u8> = words
        .iter()
        .flat_map(|&w| match (word8, be) {
            (true, false) => w.to_le_bytes().to_vec(),
            (true, true) => w.to_be_bytes().to_vec(),
            (false, false) => (w as u32).to_le_bytes().to_vec(),
            (false, true) => (w as u32).to_be_bytes().to_vec(),
        })
        .collect();
    (header, blocks.concat())
}

const ARRAY: &str = "<DataArray type=\"Int16\" Name=\"density\" NumberOfComponents=\"1\"";

#[test]
fn vti_ascii_and_inline_binary() {
    let dir = tempfile::tempdir().unwrap();
    let spacing = [0.5, 1.0, 2.0];
    // A first, non-scalar array that `Scalars` tells us to pass over.
    let text: Vec<String> = i16s().iter().map(|x| x.to_string()).collect();
    let arr = format!(
        "<DataArray type=\"Float32\" Name=\"other\" format=\"ascii\">1 2</DataArray>\n\
         {ARRAY} format=\"ascii\" RangeMin=\"-2000\">\n {}\n </DataArray>",
        text.join(" ")
    );
    let p = write(
        dir.path(),
        "ascii.vti",
        &vti("byte_order=\"LittleEndian\"", &arr, None),
    );
    assert!(is_volume_file(&p));
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Inline binary, uncompressed, UInt32 header: one base64 stream (as VTK writes it).
    let data = le16(&i16s());
    let enc = b64(&[&(data.len() as u32).to_le_bytes()[..], &data].concat());
    let arr = format!("{ARRAY} format=\"binary\">\n          {enc}\n        </DataArray>");
    let p = write(
        dir.path(),
        "bin.vti",
        &vti(
            "byte_order=\"LittleEndian\" header_type=\"UInt32\"",
            &arr,
            None,
        ),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Inline binary, uncompressed, UInt64 header encoded separately.
    let enc = b64(&(data.len() as u64).to_le_bytes()) + &b64(&data);
    let arr = format!("{ARRAY} format=\"binary\">{enc}</DataArray>");
    let p = write(
        dir.path(),
        "bin64.vti",
        &vti(
            "byte_order=\"LittleEndian\" header_type=\"UInt64\"",
            &arr,
            None,
        ),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Inline binary, zlib in 3 blocks (header and blocks encoded separately, as VTK does).
    let (h, z) = vtk_zlib(&data, 48, false, false);
    let enc = b64(&h) + &b64(&z);
    let arr = format!("{ARRAY} format=\"binary\">{enc}</DataArray>");
    let attrs = "byte_order=\"LittleEndian\" compressor=\"vtkZLibDataCompressor\"";
    let p = write(dir.path(), "zbin.vti", &vti(attrs, &arr, None));
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Big-endian, UInt64 header, zlib, header and blocks in one base64 stream.
    let (h, z) = vtk_zlib(&be16(&i16s()), 40, true, true);
    let enc = b64(&[h, z].concat());
    let arr = format!("{ARRAY} format=\"binary\">{enc}</DataArray>");
    let attrs = "byte_order=\"BigEndian\" header_type=\"UInt64\" \
                 compressor=\"vtkZLibDataCompressor\"";
    let p = write(dir.path(), "zbin64.vti", &vti(attrs, &arr, None));
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // UInt8 stays u8.
    let enc = b64(&[&60u32.to_le_bytes()[..], &u8s()].concat());
    let arr =
        format!("<DataArray type=\"UInt8\" Name=\"density\" format=\"binary\">{enc}</DataArray>");
    let p = write(dir.path(), "u8.vti", &vti("", &arr, None));
    assert_eq!(load(&p).voxels, Voxels::U8(u8s()));
}

#[test]
fn vti_appended_raw_and_base64() {
    let dir = tempfile::tempdir().unwrap();
    let spacing = [0.5, 1.0, 2.0];
    let data = le16(&i16s());
    // Another array first in the appended block, so our offset is not 0.
    let other = [&8u32.to_le_bytes()[..], &[7u8; 8]].concat();
    let ours = [&(data.len() as u32).to_le_bytes()[..], &data].concat();
    let arr = format!("{ARRAY} format=\"appended\" offset=\"{}\"/>", other.len());
    let app = [other.clone(), ours].concat();
    let p = write(
        dir.path(),
        "raw.vti",
        &vti("byte_order=\"LittleEndian\"", &arr, Some(("raw", &app))),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Raw appended, zlib blocks, UInt64 header.
    let (h, z) = vtk_zlib(&data, 64, true, false);
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\">\n        </DataArray>");
    let attrs = "byte_order=\"LittleEndian\" header_type=\"UInt64\" \
                 compressor=\"vtkZLibDataCompressor\"";
    let p = write(
        dir.path(),
        "zraw.vti",
        &vti(attrs, &arr, Some(("raw", &[h, z].concat()))),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Base64 appended, zlib (the lung1.vti layout): offset counts base64 characters.
    let other = b64(&[&4u32.to_le_bytes()[..], &[1, 2, 3, 4]].concat());
    let (h, z) = vtk_zlib(&data, 32, false, false);
    let ours = b64(&h) + &b64(&z);
    let arr = format!("{ARRAY} format=\"appended\" offset=\"{}\"/>", other.len());
    let attrs = "byte_order=\"LittleEndian\" header_type=\"UInt32\" \
                 compressor=\"vtkZLibDataCompressor\"";
    let app = other + &ours;
    let p = write(
        dir.path(),
        "zb64.vti",
        &vti(attrs, &arr, Some(("base64", app.as_bytes()))),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);

    // Base64 appended, uncompressed.
    let enc = b64(&[&(data.len() as u32).to_le_bytes()[..], &data].concat());
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\"/>");
    let p = write(
        dir.path(),
        "b64.vti",
        &vti("", &arr, Some(("base64", enc.as_bytes()))),
    );
    assert_f32(&load(&p), &as_f32(&i16s()), spacing);
}

#[test]
fn vti_errors_name_file_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let data = le16(&i16s());
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\"/>");
    // The file ends 70 bytes into the 120 data bytes.
    let whole = vti(
        "",
        &arr,
        Some(("raw", &[&120u32.to_le_bytes()[..], &data].concat())),
    );
    let cut = whole.iter().rposition(|&b| b == b'_').unwrap() + 1 + 4 + 70;
    let p = write(dir.path(), "trunc.vti", &whole[..cut]);
    expect_err(&p, &["truncated"]);

    let app = [&100u32.to_le_bytes()[..], &data].concat();
    let p = write(dir.path(), "size.vti", &vti("", &arr, Some(("raw", &app))));
    expect_err(&p, &["holds 100 bytes", "120 bytes"]);

    let attrs = "compressor=\"vtkLZ4DataCompressor\"";
    let p = write(
        dir.path(),
        "lz4.vti",
        &vti(attrs, &arr, Some(("raw", &app))),
    );
    expect_err(&p, &["unsupported compressor 'vtkLZ4DataCompressor'"]);

    let (h, mut z) = vtk_zlib(&data, 64, false, false);
    let n = z.len();
    z[n / 2] ^= 0xff;
    z[n - 3] ^= 0xff;
    let attrs = "compressor=\"vtkZLibDataCompressor\"";
    let p = write(
        dir.path(),
        "corrupt.vti",
        &vti(attrs, &arr, Some(("raw", &[h, z].concat()))),
    );
    expect_err(&p, &["zlib"]);

    let p = write(
        dir.path(),
        "type.vti",
        &vti(
            "",
            "<DataArray type=\"Int64\" Name=\"x\" format=\"ascii\">1</DataArray>",
            None,
        ),
    );
    expect_err(&p, &["unsupported type 'Int64'"]);
    let p = write(
        dir.path(),
        "vec.vti",
        &vti(
            "",
            "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">1</DataArray>",
            None,
        ),
    );
    expect_err(&p, &["3 components"]);
    let f = String::from_utf8(vti("", &arr, None))
        .unwrap()
        .replace("0 4 10 13", "4 0 10 13");
    let p = write(dir.path(), "extent.vti", f.as_bytes());
    expect_err(&p, &["non-positive"]);
    let p = write(dir.path(), "cut.vti", &vti("", &arr, None)[..150]);
    expect_err(&p, &["truncated"]);
    let p = write(
        dir.path(),
        "poly.vti",
        b"<VTKFile type=\"PolyData\"><PolyData/></VTKFile>",
    );
    expect_err(&p, &["not ImageData"]);
    let bad = format!("{ARRAY} format=\"binary\">AAAA*AAA</DataArray>");
    let p = write(dir.path(), "b64.vti", &vti("", &bad, None));
    expect_err(&p, &["base64"]);
}

// ---------------------------------------------------------------------------------------
// DICOM

const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";

/// Builds DICOM files element by element, without any DICOM library.
struct Dcm {
    explicit: bool,
    be: bool,
    body: Vec<u8>,
}

impl Dcm {
    fn new(ts: &str) -> Self {
        Dcm {
            explicit: ts != IMPLICIT_LE,
            be: ts == EXPLICIT_BE,
            body: Vec::new(),
        }
    }
    fn u16(&mut self, v: u16) {
        let b = if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.body.extend_from_slice(&b);
    }
    fn u32(&mut self, v: u32) {
        let b = if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.body.extend_from_slice(&b);
    }
    fn elem(&mut self, tag: (u16, u16), vr: &str, value: &[u8]) -> &mut Self {
        let mut v = value.to_vec();
        if v.len() % 2 == 1 {
            v.push(if vr == "UI" || vr == "OB" { 0 } else { b' ' });
        }
        self.u16(tag.0);
        self.u16(tag.1);
        if self.explicit {
            self.body.extend_from_slice(vr.as_bytes());
            if ["OB", "OW", "SQ", "UN", "UT"].contains(&vr) {
                self.body.extend_from_slice(&[0, 0]);
                self.u32(v.len() as u32);
            } else {
                self.u16(v.len() as u16);
            }
        } else {
            self.u32(v.len() as u32);
        }
        self.body.extend_from_slice(&v);
        self
    }
    fn str(&mut self, tag: (u16, u16), vr: &str, s: &str) -> &mut Self {
        self.elem(tag, vr, s.as_bytes())
    }
    fn us(&mut self, tag: (u16, u16), v: u16) -> &mut Self {
        let b = if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.elem(tag, "US", &b)
    }
    /// A sequence of undefined length with one item of undefined length holding `inner`.
    fn sequence(&mut self, tag: (u16, u16), inner: &[u8]) -> &mut Self {
        self.u16(tag.0);
        self.u16(tag.1);
        if self.explicit {
            self.body.extend_from_slice(b"SQ\0\0");
        }
        self.u32(u32::MAX);
        // One item of undefined length.
        self.u16(0xFFFE);
        self.u16(0xE000);
        self.u32(u32::MAX);
        self.body.extend_from_slice(inner);
        for t in [(0xFFFE, 0xE00D), (0xFFFE, 0xE0DD)] {
            self.u16(t.0);
            self.u16(t.1);
            self.u32(0);
        }
        self
    }
    /// Preamble, DICM, meta group (explicit VR little endian), dataset.
    fn file(&self, ts: &str) -> Vec<u8> {
        let mut meta = Dcm::new(EXPLICIT_LE);
        meta.elem((0x0002, 0x0001), "OB", &[0, 1])
            .str((0x0002, 0x0002), "UI", "1.2.840.10008.5.1.4.1.1.2")
            .str((0x0002, 0x0010), "UI", ts);
        let mut group = Dcm::new(EXPLICIT_LE);
        group.elem(
            (0x0002, 0x0000),
            "UL",
            &(meta.body.len() as u32).to_le_bytes(),
        );
        let mut f = vec![0u8; 128];
        f.extend_from_slice(b"DICM");
        f.extend_from_slice(&group.body);
        f.extend_from_slice(&meta.body);
        f.extend_from_slice(&self.body);
        f
    }
}

struct SliceSpec<'a> {
    series: &'a str,
    position: Option<[f64; 3]>,
    instance: i32,
    slope: f64,
    intercept: f64,
    signed: bool,
    pixels: Vec<u8>,
}

/// A 5×4 CT-like slice: rows 4, columns 5, 16 bits.
fn slice_file(ts: &str, s: &SliceSpec, orientation: &str) -> Vec<u8> {
    let mut d = Dcm::new(ts);
    d.str((0x0008, 0x0016), "UI", "1.2.840.10008.5.1.4.1.1.2")
        .str((0x0008, 0x0060), "CS", "CT");
    // A nested sequence (undefined lengths) that the reader must skip.
    let mut inner = Dcm::new(ts);
    inner
        .str((0x0008, 0x0100), "SH", "CODE")
        .str((0x0008, 0x0104), "LO", "meaning");
    d.sequence((0x0008, 0x1032), &inner.body);
    d.str((0x0018, 0x0050), "DS", "2.5")
        .str((0x0020, 0x000D), "UI", "1.2.3.4")
        .str((0x0020, 0x000E), "UI", s.series)
        .str((0x0020, 0x0013), "IS", &s.instance.to_string());
    if let Some(p) = s.position {
        d.str(
            (0x0020, 0x0032),
            "DS",
            &format!("{}\\{}\\{}", p[0], p[1], p[2]),
        )
        .str((0x0020, 0x0037), "DS", orientation);
    }
    d.us((0x0028, 0x0002), 1)
        .str((0x0028, 0x0004), "CS", "MONOCHROME2")
        .us((0x0028, 0x0010), 4)
        .us((0x0028, 0x0011), 5)
        .str((0x0028, 0x0030), "DS", "0.75\\0.5")
        .us((0x0028, 0x0100), 16)
        .us((0x0028, 0x0101), 16)
        .us((0x0028, 0x0102), 15)
        .us((0x0028, 0x0103), s.signed as u16)
        .str((0x0028, 0x1052), "DS", &s.intercept.to_string())
        .str((0x0028, 0x1053), "DS", &s.slope.to_string())
        .elem((0x7FE0, 0x0010), "OW", &s.pixels);
    d.file(ts)
}

/// Writes a 3-slice series into `dir` with file names in reverse slice order.
fn write_series(dir: &Path, ts: &str, signed: bool, slope: f64, intercept: f64, be: bool) {
    for z in 0..3 {
        let px = if signed {
            let v = &i16s()[z * 20..z * 20 + 20];
            if be {
                be16(v)
            } else {
                le16(v)
            }
        } else {
            let v = &u16s()[z * 20..z * 20 + 20];
            if be {
                be_u16(v)
            } else {
                le_u16(v)
            }
        };
        let spec = SliceSpec {
            series: "1.2.3.4.5",
            position: Some([-10.0, 20.0, 100.0 + 2.5 * z as f64]),
            instance: z as i32 + 1,
            slope,
            intercept,
            signed,
            pixels: px,
        };
        write(
            dir,
            &format!("IM{:04}.dcm", 9 - z),
            &slice_file(ts, &spec, "1\\0\\0\\0\\1\\0"),
        );
    }
}

#[test]
fn dicom_series_implicit_le_sorted_and_rescaled() {
    let dir = tempfile::tempdir().unwrap();
    write_series(dir.path(), IMPLICIT_LE, true, 1.0, -1024.0, false);
    write(dir.path(), "README.txt", b"not a DICOM file");
    assert!(is_volume_file(dir.path()));
    let v = load(dir.path());
    let want: Vec<f32> = i16s().iter().map(|&x| x as f32 - 1024.0).collect();
    assert_f32(&v, &want, [0.5, 0.75, 2.5]);
    assert_eq!(v.range, None);
    let v = load_opts(
        dir.path(),
        &LoadOptions {
            window: Some((-1000.0, 2000.0)),
            ..Default::default()
        },
    );
    assert_eq!(v.range, Some((-1000.0, 2000.0)));
}

#[test]
fn dicom_series_explicit_le_and_be() {
    let dir = tempfile::tempdir().unwrap();
    write_series(dir.path(), EXPLICIT_LE, false, 1.0, 0.0, false);
    let v = load(dir.path());
    assert_eq!(v.voxels, Voxels::U16(u16s()));
    assert_eq!(v.spacing, [0.5, 0.75, 2.5]);

    let dir = tempfile::tempdir().unwrap();
    write_series(dir.path(), EXPLICIT_BE, true, 2.0, 1.0, true);
    let want: Vec<f32> = i16s().iter().map(|&x| x as f32 * 2.0 + 1.0).collect();
    assert_f32(&load(dir.path()), &want, [0.5, 0.75, 2.5]);
}

#[test]
fn dicom_series_oblique_and_instance_number_order() {
    // Rows along x, columns along z: the slice normal is x × z = -y, so the slice at the
    // most negative y·(-1), i.e. the largest y, comes first.
    let dir = tempfile::tempdir().unwrap();
    for z in 0..3 {
        let spec = SliceSpec {
            series: "9.9",
            position: Some([0.0, 50.0 - 3.0 * z as f64, 0.0]),
            instance: 10 - z as i32,
            slope: 1.0,
            intercept: 0.0,
            signed: true,
            pixels: le16(&i16s()[z * 20..z * 20 + 20]),
        };
        write(
            dir.path(),
            &format!("s{z}"),
            &slice_file(EXPLICIT_LE, &spec, "1\\0\\0\\0\\0\\1"),
        );
    }
    assert_f32(&load(dir.path()), &as_f32(&i16s()), [0.5, 0.75, 3.0]);

    // No positions: InstanceNumber order, SliceThickness as spacing.
    let dir = tempfile::tempdir().unwrap();
    for z in 0..3 {
        let spec = SliceSpec {
            series: "9.9",
            position: None,
            instance: 7 + z as i32,
            slope: 1.0,
            intercept: 0.0,
            signed: true,
            pixels: le16(&i16s()[z * 20..z * 20 + 20]),
        };
        write(
            dir.path(),
            &format!("z{}", 5 - z),
            &slice_file(IMPLICIT_LE, &spec, ""),
        );
    }
    assert_f32(&load(dir.path()), &as_f32(&i16s()), [0.5, 0.75, 2.5]);
}

#[test]
fn dicom_errors_name_directory_and_reason() {
    let spec = |series: &'static str, z: f64, instance: i32| SliceSpec {
        series,
        position: Some([0.0, 0.0, z]),
        instance,
        slope: 1.0,
        intercept: 0.0,
        signed: false,
        pixels: vec![0; 40],
    };
    let axial = "1\\0\\0\\0\\1\\0";

    // Mixed series: both UIDs named.
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "a",
        &slice_file(EXPLICIT_LE, &spec("1.1", 0.0, 1), axial),
    );
    write(
        dir.path(),
        "b",
        &slice_file(EXPLICIT_LE, &spec("1.1", 1.0, 2), axial),
    );
    write(
        dir.path(),
        "c",
        &slice_file(EXPLICIT_LE, &spec("2.2", 0.0, 1), axial),
    );
    expect_err(
        dir.path(),
        &["mixed DICOM series", "1.1 (2 files)", "2.2 (1 files)"],
    );

    // A missing slice: the gap is named.
    let dir = tempfile::tempdir().unwrap();
    for (i, z) in [0.0, 2.0, 4.0, 8.0, 10.0].iter().enumerate() {
        write(
            dir.path(),
            &format!("s{i}"),
            &slice_file(EXPLICIT_LE, &spec("1", *z, 1), axial),
        );
    }
    expect_err(
        dir.path(),
        &[
            "missing slices",
            "gap of 4.0000",
            "4.0000 ('s2')",
            "8.0000 ('s3')",
        ],
    );

    // Duplicate positions.
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "a",
        &slice_file(EXPLICIT_LE, &spec("1", 0.0, 1), axial),
    );
    write(
        dir.path(),
        "b",
        &slice_file(EXPLICIT_LE, &spec("1", 0.0, 2), axial),
    );
    expect_err(dir.path(), &["same slice position"]);

    // Compressed transfer syntax: the syntax is named.
    let dir = tempfile::tempdir().unwrap();
    let jpeg = "1.2.840.10008.1.2.4.70";
    let mut ds = Dcm::new(EXPLICIT_LE);
    ds.str((0x0020, 0x000E), "UI", "1")
        .us((0x0028, 0x0010), 4)
        .elem((0x7FE0, 0x0010), "OB", &[0; 40]);
    let f = ds.file(jpeg);
    write(dir.path(), "jpeg.dcm", &f);
    expect_err(dir.path(), &[jpeg, "JPEG Lossless", "not supported"]);

    // A truncated file: its name and the reason.
    let dir = tempfile::tempdir().unwrap();
    let f = slice_file(EXPLICIT_LE, &spec("1", 0.0, 1), axial);
    write(dir.path(), "cut.dcm", &f[..f.len() - 7]);
    expect_err(dir.path(), &["cut.dcm", "truncated"]);

    // Pixel data of the wrong size.
    let dir = tempfile::tempdir().unwrap();
    let mut s = spec("1", 0.0, 1);
    s.pixels = vec![0; 30];
    write(dir.path(), "small.dcm", &slice_file(EXPLICIT_LE, &s, axial));
    expect_err(dir.path(), &["small.dcm", "30 bytes", "40 bytes"]);

    // A single file instead of the directory.
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "one.dcm",
        &slice_file(EXPLICIT_LE, &spec("1", 0.0, 1), axial),
    );
    expect_err(&p, &["directory"]);

    // No DICOM files at all.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "notes.txt", b"hello");
    assert!(!is_volume_file(dir.path()));
    expect_err(dir.path(), &["no DICOM image files"]);
}

// ---------------------------------------------------------------------------------------
// No panics on damaged input

/// One valid small file of each format and encoding (DICOM: a series directory).
fn sample_files(dir: &Path) -> Vec<PathBuf> {
    let raw16 = le16(&i16s());
    let nrrd_h = "type: short\ndimension: 3\nsizes: 5 4 3\nspacings: 1 1 2\nendian: little\n";
    let (vh, vz) = vtk_zlib(&raw16, 48, true, false);
    let vti_attrs = "byte_order=\"LittleEndian\" header_type=\"UInt64\" \
                     compressor=\"vtkZLibDataCompressor\"";
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\"/>");
    let app = b64(&vh) + &b64(&vz);
    let inline = b64(&[&120u32.to_le_bytes()[..], &raw16].concat());
    let nii = [
        nifti_header(&[5, 4, 3], 4, 16, [1.0; 3], 352.0, 2.0, 1.0, false),
        raw16.clone(),
    ]
    .concat();
    let mha = mhd("CompressedData = True\nElementType = MET_SHORT\n", "LOCAL");
    let dicom = dir.join("series");
    std::fs::create_dir_all(&dicom).unwrap();
    write_series(&dicom, EXPLICIT_LE, true, 1.0, -1024.0, false);
    vec![
        write(dir, "a_5x4x3_int16.raw", &raw16),
        write(
            dir,
            "a.nrrd",
            &nrrd(&format!("{nrrd_h}encoding: raw\n"), &raw16),
        ),
        write(
            dir,
            "b.nrrd",
            &nrrd(&format!("{nrrd_h}encoding: gzip\n"), &gzip(&raw16)),
        ),
        write(dir, "a.nii", &nii),
        write(dir, "b.nii.gz", &gzip(&nii)),
        write(dir, "a.mha", &[mha.as_bytes(), &zlib(&raw16)].concat()),
        write(
            dir,
            "a.vti",
            &vti(vti_attrs, &arr, Some(("base64", app.as_bytes()))),
        ),
        write(
            dir,
            "b.vti",
            &vti(
                "",
                &format!("{ARRAY} format=\"binary\">{inline}</DataArray>"),
                None,
            ),
        ),
        dicom.join("IM0008.dcm"),
    ]
}

#[test]
fn no_panics_on_truncated_or_mutated_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut seed = 0x1234_5678_9abc_def0u64;
    let mut rand = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as usize
    };
    for path in sample_files(dir.path()) {
        let target = if path.extension().is_some_and(|e| e == "dcm") {
            path.parent().unwrap().to_path_buf()
        } else {
            path.clone()
        };
        let good = std::fs::read(&path).unwrap();
        load_volume(&target, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("the undamaged file must load: {e}"));
        let step = (good.len() / 150).max(1);
        for cut in (0..good.len()).step_by(step) {
            std::fs::write(&path, &good[..cut]).unwrap();
            if let Err(e) = load_volume(&target, &LoadOptions::default()) {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
        }
        for _ in 0..300 {
            let mut bad = good.clone();
            for _ in 0..1 + rand() % 4 {
                let i = rand() % bad.len();
                bad[i] = match rand() % 4 {
                    0 => 0,
                    1 => 0xff,
                    2 => b'9',
                    _ => rand() as u8,
                };
            }
            std::fs::write(&path, &bad).unwrap();
            let _ = load_volume(&target, &LoadOptions::default());
        }
        std::fs::write(&path, &good).unwrap();
    }
}

// ---------------------------------------------------------------------------------------
// Size guard

#[test]
fn check_limits_reports_the_limit() {
    check_limits([512, 512, 48], 2048, Some(1 << 30)).unwrap();
    let e = check_limits([4096, 512, 48], 2048, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("maxImageDimension3D") && e.contains("2048") && e.contains("4096"),
        "{e}"
    );
    let e = check_limits([2048, 2048, 2048], 2048, Some(1 << 33))
        .unwrap_err()
        .to_string();
    assert!(e.contains("bytes available"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Real files from scripts/fetch-data.

fn data_dir() -> PathBuf {
    refrakt::scene::data_dir()
}

fn require_data() -> bool {
    std::env::var("REFRAKT_REQUIRE_DATA").is_ok_and(|v| v != "0")
}

/// The real file, or `None` (test skipped) when it is missing and data is not required.
fn real(name: &str) -> Option<PathBuf> {
    let p = data_dir().join(name);
    if p.exists() {
        return Some(p);
    }
    assert!(
        !require_data(),
        "{} is missing and REFRAKT_REQUIRE_DATA is set (run scripts/fetch-data)",
        p.display()
    );
    println!(
        "skipped: {} not found (run scripts/fetch-data)",
        p.display()
    );
    None
}

fn lung1_nrrd() -> Option<&'static Volume> {
    static V: std::sync::OnceLock<Option<Volume>> = std::sync::OnceLock::new();
    V.get_or_init(|| real("ct/lung1_image.nrrd").map(|p| load(&p)))
        .as_ref()
}

/// The same array as the NRRD: voxel by voxel (and, when `spacing`, the same voxel size).
fn assert_same_as_lung1(name: &str, spacing: bool) {
    let Some(p) = real(name) else { return };
    let Some(reference) = lung1_nrrd() else {
        return;
    };
    let v = load(&p);
    assert_eq!(v.dims, [512, 512, 48], "{name}");
    if spacing {
        for (a, b) in v.spacing.iter().zip(&reference.spacing) {
            assert!(
                (a - b).abs() <= 1e-3 * b.abs().max(1.0),
                "{name}: spacing {:?} vs NRRD {:?}",
                v.spacing,
                reference.spacing
            );
        }
    }
    // The patient orientation, where the format states it: the NRRD's LPS space
    // directions, read back through NIfTI's RAS sform/qform or DICOM's
    // ImageOrientationPatient (written by other tools), must agree.
    // MetaImage's TransformMatrix is in ITK's LPS frame. VTK's Direction is not anatomical:
    // the identity the file holds places the voxel axes in the renderer's world as they are
    // (x right = L, y up = S, z towards the viewer = A), not the NRRD's LPS.
    let stated = name.contains(".nii") || name.contains("dicom") || name.contains(".mh");
    if name.ends_with(".vti") {
        let world = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];
        assert_eq!(v.axes, Some(world), "{name}: the identity Direction");
    } else {
        match (v.axes, reference.axes) {
            (Some(a), Some(b)) => {
                let close = a
                    .iter()
                    .flatten()
                    .zip(b.iter().flatten())
                    .all(|(x, y)| (x - y).abs() < 1e-3);
                assert!(close, "{name}: voxel axes {a:?}, the NRRD's {b:?}");
            }
            (None, Some(_)) => assert!(!stated, "{name}: no orientation read"),
            (_, None) => panic!("the NRRD states its space directions; none read"),
        }
    }
    let (Voxels::F32(got), Voxels::F32(want)) = (&v.voxels, &reference.voxels) else {
        panic!(
            "{name}: expected f32 voxels from int16 CT, got {}",
            v.voxels.type_name()
        );
    };
    if got != want {
        let i = got.iter().zip(want).position(|(a, b)| a != b).unwrap_or(0);
        let slice = 512 * 512;
        let flipped: Vec<f32> = want.chunks(slice).rev().flatten().copied().collect();
        panic!(
            "{name}: voxel {i} is {} but the NRRD has {}{}",
            got[i],
            want[i],
            if *got == flipped {
                " (the slices are in reverse order)"
            } else {
                ""
            }
        );
    }
}

#[test]
fn real_lung1_nrrd() {
    let Some(v) = lung1_nrrd() else { return };
    assert_eq!(v.dims, [512, 512, 48]);
    let Voxels::F32(x) = &v.voxels else {
        panic!("int16 CT should load as f32, got {}", v.voxels.type_name())
    };
    let (lo, hi) = x
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(
        lo >= -32768.0 && hi <= 32767.0 && lo < -500.0 && hi > 500.0,
        "CT range {lo}..{hi}"
    );
    assert!(
        v.spacing.iter().all(|s| *s > 0.1 && *s < 10.0),
        "{:?}",
        v.spacing
    );
}

#[test]
fn real_ch2_nifti() {
    let Some(p) = real("mri/ch2.nii.gz") else {
        return;
    };
    let v = load(&p);
    assert_eq!(v.dims, [181, 217, 181]);
    assert!(
        matches!(v.voxels, Voxels::U8(_)),
        "ch2 is u8, got {}",
        v.voxels.type_name()
    );
    assert_eq!(v.spacing, [1.0, 1.0, 1.0]);
}

#[test]
fn real_lung1_mha_matches_nrrd() {
    assert_same_as_lung1("formats/lung1.mha", true);
}

#[test]
fn real_lung1_mhd_matches_nrrd() {
    assert_same_as_lung1("formats/lung1.mhd", true);
}

#[test]
fn real_lung1_vti_matches_nrrd() {
    assert_same_as_lung1("formats/lung1.vti", true);
}

#[test]
fn real_lung1_dicom_matches_nrrd() {
    assert_same_as_lung1("formats/lung1_dicom", true);
}

#[test]
fn real_lung1_nifti_matches_nrrd() {
    assert_same_as_lung1("formats/lung1.nii.gz", true);
}

#[test]
fn real_lung1_raw_matches_nrrd() {
    assert_same_as_lung1("formats/lung1_512x512x48_int16.raw", false);
}

/// "How to add a format" (docs/ARCHITECTURE.md) held honest: every format of the
/// registry (`formats::FORMATS`) has its row in docs/FORMATS.md's table naming each of
/// its extensions, a file so named is a volume file, and an unknown name's error lists
/// every extension. A format added to the registry without its documentation, or
/// documented without being registered, fails here.
#[test]
fn every_registered_format_is_documented_and_recognised() {
    use refrakt::volume::formats::{known_extensions, Format, FORMATS};
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/FORMATS.md"))
            .unwrap();
    let table: Vec<&str> = doc.lines().filter(|l| l.starts_with("| ")).collect();
    for f in FORMATS {
        let row = table
            .iter()
            .find(|l| l.starts_with(&format!("| {} |", f.name)))
            .unwrap_or_else(|| panic!("docs/FORMATS.md has no row for {}", f.name));
        for ext in f.extensions {
            assert!(
                row.contains(&format!("`{ext}`")),
                "{}: {ext} not in its row",
                f.name
            );
            // Not read: a name is enough (any case).
            let path = PathBuf::from(format!("volume{}", ext.to_uppercase()));
            assert!(is_volume_file(&path), "{}", path.display());
            assert_eq!(Format::of(&path).map(|g| g.name), Some(f.name));
        }
    }
    // Every format row of the table is registered (the DICOM series is read from a
    // directory, not by name).
    let header = table
        .iter()
        .position(|l| l.starts_with("| format |"))
        .unwrap();
    for row in table[header + 2..]
        .iter()
        .take_while(|l| !l.contains("DICOM series"))
    {
        let name = row.split('|').nth(1).unwrap().trim();
        assert!(
            FORMATS.iter().any(|f| f.name == name),
            "docs/FORMATS.md documents '{name}', which formats::FORMATS does not register"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "volume.xyz", b"not a volume");
    let err = format!(
        "{:#}",
        load_volume(&path, &LoadOptions::default()).unwrap_err()
    );
    for ext in known_extensions() {
        assert!(err.contains(ext), "{err}");
    }
}

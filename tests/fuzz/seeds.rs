//! Valid seed files of every format `tests/fuzz.rs` fuzzes, built byte by byte here (as
//! tests/formats.rs, tests/scenes.rs and tests/environment.rs build theirs), with what the
//! mutator needs to know about each: where its text header ends, where its binary header
//! numbers are, and whether it is written compressed.

use std::io::Write;

use flate2::write::{GzEncoder, ZlibEncoder};
use flate2::Compression;
use refrakt::volume::formats::{RawLayout, ScalarKind};

use crate::dicom::{self, Elem, Spec, Value};
use crate::mutate::Field;

#[path = "../common/samples.rs"]
mod samples;
use samples::*;

/// How a seed file is written after it is mutated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Post {
    None,
    /// Written gzip-compressed; mostly the content is mutated, sometimes the stream.
    Gzip,
    /// A PNG: mostly its chunk checksums are repaired after the mutation.
    Png,
}

#[derive(Clone, Debug)]
pub struct SeedFile {
    pub name: String,
    pub bytes: Vec<u8>,
    /// Bytes `0..text_len` are a text header (line, number and word mutations).
    pub text_len: usize,
    /// Numbers in a binary header.
    pub fields: Vec<Field>,
    /// Relative chance to be the file a case mutates (0: never; it is written as is).
    pub weight: u32,
    pub post: Post,
    /// The name holds the layout (`<name>_<X>x<Y>x<Z>_<type>.raw`): mutate it too.
    pub name_mutable: bool,
    /// A DICOM file as elements, for value-level mutations.
    pub dicom: Option<Spec>,
}

impl SeedFile {
    pub fn binary(name: &str, bytes: Vec<u8>) -> Self {
        SeedFile {
            name: name.into(),
            bytes,
            text_len: 0,
            fields: Vec::new(),
            weight: 1,
            post: Post::None,
            name_mutable: false,
            dicom: None,
        }
    }
    /// A file whose first `text_len` bytes are a text header.
    pub fn header(name: &str, bytes: Vec<u8>, text_len: usize) -> Self {
        SeedFile {
            text_len,
            ..Self::binary(name, bytes)
        }
    }
    pub fn text(name: &str, text: &str) -> Self {
        Self::header(name, text.as_bytes().to_vec(), text.len())
    }
    fn weight(mut self, w: u32) -> Self {
        self.weight = w;
        self
    }
    fn fields(mut self, f: Vec<Field>) -> Self {
        self.fields = f;
        self
    }
    fn post(mut self, p: Post) -> Self {
        self.post = p;
        self
    }
}

#[derive(Clone, Debug)]
pub struct Seed {
    pub label: String,
    pub files: Vec<SeedFile>,
    /// The file given to the parser; `None`: the directory (a DICOM series).
    pub entry: Option<usize>,
    /// Read as headerless raw data with this layout.
    pub raw: Option<RawLayout>,
}

fn seed(label: &str, files: Vec<SeedFile>) -> Seed {
    Seed {
        label: label.into(),
        files,
        entry: Some(0),
        raw: None,
    }
}

// ---------------------------------------------------------------------------------------
// Data

fn be_f64(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

pub fn gzip(data: &[u8]) -> Vec<u8> {
    let mut e = GzEncoder::new(Vec::new(), Compression::fast());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}
fn zlib(data: &[u8]) -> Vec<u8> {
    let mut e = ZlibEncoder::new(Vec::new(), Compression::fast());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}
fn cat(a: &[u8], b: &[u8]) -> Vec<u8> {
    [a, b].concat()
}

// ---------------------------------------------------------------------------------------
// raw

pub fn raw() -> Vec<Seed> {
    let named = |name: &str, bytes: Vec<u8>| {
        let mut f = SeedFile::binary(name, bytes);
        f.name_mutable = true;
        seed(name, vec![f])
    };
    let mut explicit = seed(
        "explicit layout u16",
        vec![SeedFile::binary("vol.bin", le_u16(&u16s()))],
    );
    explicit.raw = Some(RawLayout {
        dims: DIMS,
        kind: ScalarKind::U16,
        spacing: Some([1.0, 1.0, 2.0]),
    });
    let mut explicit_f32 = seed(
        "explicit layout f32",
        vec![SeedFile::binary("vol.dat", le_f32(&f32s()))],
    );
    explicit_f32.raw = Some(RawLayout {
        dims: DIMS,
        kind: ScalarKind::F32,
        spacing: None,
    });
    vec![
        named("a_5x4x3_int16.raw", le16(&i16s())),
        named("b_5x4x3_uint8.raw", u8s()),
        named("c_5x4x3_float32.raw", le_f32(&f32s())),
        named("d_5x4x3_uint16.raw", le_u16(&u16s())),
        explicit,
        explicit_f32,
    ]
}

// ---------------------------------------------------------------------------------------
// NRRD

/// An attached NRRD file: header, blank line, data.
fn nrrd(fields: &str, data: &[u8]) -> SeedFile {
    let header = format!("NRRD0004\n# Complete NRRD file format specification at:\n{fields}\n");
    SeedFile::header("a.nrrd", cat(header.as_bytes(), data), header.len())
}

pub fn nrrd_seeds() -> Vec<Seed> {
    let ascii: Vec<String> = u8s().iter().map(|x| x.to_string()).collect();
    let dbl: Vec<f64> = (0..N).map(|i| i as f64 / 8.0).collect();
    let crlf = {
        let h = "NRRD0004\r\ntype: uint8\r\ndimension: 3\r\nsizes: 5 4 3\r\nencoding: raw\r\n\r\n";
        SeedFile::header("a.nrrd", cat(h.as_bytes(), &u8s()), h.len())
    };
    let detached = |header: &str, data_name: &str, data: Vec<u8>| {
        vec![
            SeedFile::text("a.nhdr", header).weight(3),
            SeedFile::binary(data_name, data),
        ]
    };
    vec![
        seed(
            "attached raw int16, space directions",
            vec![nrrd(
                "type: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 5 4 3\n\
                 space directions: (0.5,0,0) (0,0.75,0) (0,0,2.5)\nkinds: domain domain \
                 domain\nendian: little\nencoding: raw\nspace origin: (1,2,3)\n",
                &le16(&i16s()),
            )],
        ),
        seed(
            "attached gzip ushort big-endian",
            vec![nrrd(
                "type: ushort\ndimension: 3\nsizes: 5 4 3\nspacings: 1 2 3\nendian: big\n\
                 encoding: gzip\nmeta:=data\n",
                &gzip(&be_u16(&u16s())),
            )],
        ),
        seed(
            "attached ascii uchar",
            vec![nrrd(
                "type: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: ascii\n",
                ascii.join(" ").as_bytes(),
            )],
        ),
        seed(
            "attached raw double big-endian",
            vec![nrrd(
                "type: double\ndimension: 3\nsizes: 5 4 3\nendian: big\nencoding: raw\n",
                &be_f64(&dbl),
            )],
        ),
        seed("attached raw uint8, CRLF", vec![crlf]),
        seed(
            "detached raw int16",
            detached(
                "NRRD0005\ntype: int16\ndimension: 3\nsizes: 5 4 3\nendian: little\n\
                 encoding: raw\ndata file: vol.raw\n",
                "vol.raw",
                le16(&i16s()),
            ),
        ),
        seed(
            "detached gzip, line skip and byte skip",
            detached(
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: gzip\n\
                 line skip: 1\nbyte skip: 7\ndatafile: vol.raw.gz\n\n",
                "vol.raw.gz",
                cat(b"a comment line\n", &gzip(&cat(&[9u8; 7], &u8s()))),
            ),
        ),
        seed(
            "detached raw, byte skip -1",
            detached(
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 4 3\nencoding: raw\n\
                 byte skip: -1\ndata file: tail.bin\n",
                "tail.bin",
                cat(&[1u8; 33], &u8s()),
            ),
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// NIfTI-1

/// A NIfTI-1 header of `vox_offset` bytes and the offsets of its numbers.
#[allow(clippy::too_many_arguments)]
fn nifti_header_fields(
    dims: &[i16],
    datatype: i16,
    bitpix: i16,
    pixdim: [f32; 3],
    vox_offset: f32,
    slope: f32,
    inter: f32,
    be: bool,
) -> (Vec<u8>, Vec<Field>) {
    let h = nifti_header(dims, datatype, bitpix, pixdim, vox_offset, slope, inter, be);
    let mut fields = vec![
        Field::int(0, 4, be),
        Field::int(70, 2, be),
        Field::int(72, 2, be),
    ];
    fields.extend((0..8).map(|i| Field::int(40 + 2 * i, 2, be)));
    fields.extend((0..8).map(|i| Field::float(76 + 4 * i, be)));
    fields.extend([108, 112, 116].map(|o| Field::float(o, be)));
    (h, fields)
}

pub fn nifti() -> Vec<Seed> {
    let d = [5, 4, 3];
    let nii = |name: &str, (h, fields): (Vec<u8>, Vec<Field>), data: &[u8]| {
        SeedFile::binary(name, cat(&h, data)).fields(fields)
    };
    let ints: Vec<i32> = (0..N as i32).map(|i| 100_000 - i * 3).collect();
    let ints: Vec<u8> = ints.iter().flat_map(|x| x.to_le_bytes()).collect();
    vec![
        seed(
            "uint8 with pixdim",
            vec![nii(
                "a.nii",
                nifti_header_fields(&d, 2, 8, [0.9, 1.1, 2.0], 352.0, 0.0, 0.0, false),
                &u8s(),
            )],
        ),
        seed(
            "uint16 with scl_slope",
            vec![nii(
                "b.nii",
                nifti_header_fields(&d, 512, 16, [1.0; 3], 352.0, 2.0, -5.0, false),
                &le_u16(&u16s()),
            )],
        ),
        seed(
            "int16 big-endian 4-D, extension",
            vec![nii(
                "d.nii",
                nifti_header_fields(&[5, 4, 3, 1], 4, 16, [1.0; 3], 400.0, 0.0, 0.0, true),
                &be16(&i16s()),
            )],
        ),
        seed(
            "int32",
            vec![nii(
                "f.nii",
                nifti_header_fields(&d, 8, 32, [1.0; 3], 352.0, 0.0, 0.0, false),
                &ints,
            )],
        ),
        seed(
            "float32 gzip",
            vec![nii(
                "e.nii.gz",
                nifti_header_fields(&d, 16, 32, [2.0; 3], 352.0, 0.0, 0.0, false),
                &le_f32(&f32s()),
            )
            .post(Post::Gzip)],
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// MetaImage

pub fn metaimage() -> Vec<Seed> {
    let local = |name: &str, header: String, data: &[u8]| {
        SeedFile::header(name, cat(header.as_bytes(), data), header.len())
    };
    let detached = |name: &str, header: String, data_name: &str, data: Vec<u8>| {
        vec![
            SeedFile::text(name, &header).weight(3),
            SeedFile::binary(data_name, data),
        ]
    };
    let z = zlib(&le_f32(&f32s()));
    let ascii: Vec<String> = u8s().iter().map(|x| x.to_string()).collect();
    vec![
        seed(
            "mha local int16 with spacing",
            vec![local(
                "a.mha",
                mhd(
                    "BinaryData = True\nBinaryDataByteOrderMSB = False\n\
                     ElementSpacing = 0.5 0.5 2\nElementType = MET_SHORT\n",
                    "LOCAL",
                ),
                &le16(&i16s()),
            )],
        ),
        seed(
            "mha zlib float with CompressedDataSize",
            vec![local(
                "b.mha",
                mhd(
                    &format!(
                        "BinaryData = True\nCompressedData = True\nCompressedDataSize = {}\n\
                         ElementType = MET_FLOAT\n",
                        z.len()
                    ),
                    "LOCAL",
                ),
                &z,
            )],
        ),
        seed(
            "mha ascii uchar",
            vec![local(
                "f.mha",
                mhd("BinaryData = False\nElementType = MET_UCHAR\n", "LOCAL"),
                ascii.join(" ").as_bytes(),
            )],
        ),
        seed(
            "mhd big-endian ushort",
            detached(
                "c.mhd",
                mhd(
                    "BinaryData = True\nBinaryDataByteOrderMSB = True\nElementSize = 1 2 3\n\
                     ElementType = MET_USHORT\n",
                    "c.raw",
                ),
                "c.raw",
                be_u16(&u16s()),
            ),
        ),
        seed(
            "mhd zlib uchar",
            detached(
                "d.mhd",
                mhd(
                    "CompressedData = True\nElementSpacing = 1 1 1\nElementType = MET_UCHAR\n",
                    "d.zraw",
                ),
                "d.zraw",
                zlib(&u8s()),
            ),
        ),
        seed(
            "mhd HeaderSize 16, CRLF",
            detached(
                "e.mhd",
                mhd("HeaderSize = 16\nElementType = MET_SHORT\n", "e.raw").replace('\n', "\r\n"),
                "e.raw",
                cat(&[0u8; 16], &le16(&i16s())),
            ),
        ),
        seed(
            "mhd HeaderSize -1",
            detached(
                "g.mhd",
                mhd("HeaderSize = -1\nElementType = MET_UCHAR\n", "g.raw"),
                "g.raw",
                cat(&[3u8; 21], &u8s()),
            ),
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// VTK XML ImageData

const ARRAY: &str = "<DataArray type=\"Int16\" Name=\"density\" NumberOfComponents=\"1\"";

/// A .vti file; the text header ends at the appended data's `_` marker (or the end).
fn vti(name: &str, attrs: &str, array: &str, appended: Option<(&str, &[u8])>) -> SeedFile {
    let mut f = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" {attrs}>\n  \
         <ImageData WholeExtent=\"0 4 10 13 -1 1\" Origin=\"0 0 0\" Spacing=\"0.5 1 2\">\n    \
         <Piece Extent=\"0 4 10 13 -1 1\">\n      <PointData Scalars=\"density\">\n        \
         {array}\n      </PointData>\n      <CellData>\n      </CellData>\n    </Piece>\n  \
         </ImageData>\n"
    )
    .into_bytes();
    let mut text_len = None;
    if let Some((enc, data)) = appended {
        f.extend(format!("  <AppendedData encoding=\"{enc}\">\n   _").bytes());
        text_len = Some(f.len());
        f.extend_from_slice(data);
        f.extend(b"\n  </AppendedData>\n");
    }
    f.extend(b"</VTKFile>\n");
    let len = f.len();
    SeedFile::header(name, f, text_len.unwrap_or(len))
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

pub fn vti_seeds() -> Vec<Seed> {
    let data = le16(&i16s());
    let text: Vec<String> = i16s().iter().map(|x| x.to_string()).collect();
    let mut seeds = Vec::new();
    let arr = format!(
        "<DataArray type=\"Float32\" Name=\"other\" format=\"ascii\">1 2</DataArray>\n\
         {ARRAY} format=\"ascii\" RangeMin=\"-2000\">\n {}\n </DataArray>",
        text.join(" ")
    );
    seeds.push(seed(
        "ascii",
        vec![vti("a.vti", "byte_order=\"LittleEndian\"", &arr, None)],
    ));
    let enc = b64(&cat(&(data.len() as u32).to_le_bytes(), &data));
    let arr = format!("{ARRAY} format=\"binary\">\n          {enc}\n        </DataArray>");
    seeds.push(seed(
        "inline base64, UInt32 header, one stream",
        vec![vti(
            "a.vti",
            "byte_order=\"LittleEndian\" header_type=\"UInt32\"",
            &arr,
            None,
        )],
    ));
    let enc = b64(&(data.len() as u64).to_le_bytes()) + &b64(&data);
    let arr = format!("{ARRAY} format=\"binary\">{enc}</DataArray>");
    seeds.push(seed(
        "inline base64, UInt64 header, separate",
        vec![vti(
            "a.vti",
            "byte_order=\"LittleEndian\" header_type=\"UInt64\"",
            &arr,
            None,
        )],
    ));
    let (h, z) = vtk_zlib(&data, 48, false, false);
    let arr = format!(
        "{ARRAY} format=\"binary\">{}</DataArray>",
        b64(&h) + &b64(&z)
    );
    seeds.push(seed(
        "inline base64 zlib, 3 blocks",
        vec![vti(
            "a.vti",
            "byte_order=\"LittleEndian\" compressor=\"vtkZLibDataCompressor\"",
            &arr,
            None,
        )],
    ));
    let (h, z) = vtk_zlib(&be16(&i16s()), 40, true, true);
    let arr = format!(
        "{ARRAY} format=\"binary\">{}</DataArray>",
        b64(&cat(&h, &z))
    );
    seeds.push(seed(
        "inline base64 zlib big-endian UInt64, one stream",
        vec![vti(
            "a.vti",
            "byte_order=\"BigEndian\" header_type=\"UInt64\" \
             compressor=\"vtkZLibDataCompressor\"",
            &arr,
            None,
        )],
    ));
    // Appended raw: another array first, so the offset is not 0.
    let other = cat(&8u32.to_le_bytes(), &[7u8; 8]);
    let ours = cat(&(data.len() as u32).to_le_bytes(), &data);
    let arr = format!("{ARRAY} format=\"appended\" offset=\"{}\"/>", other.len());
    let mut f = vti(
        "a.vti",
        "byte_order=\"LittleEndian\"",
        &arr,
        Some(("raw", &cat(&other, &ours))),
    );
    f.fields = vec![
        Field::int(f.text_len, 4, false),
        Field::int(f.text_len + 12, 4, false),
    ];
    seeds.push(seed("appended raw", vec![f]));
    let (h, z) = vtk_zlib(&data, 64, true, false);
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\">\n        </DataArray>");
    let mut f = vti(
        "a.vti",
        "byte_order=\"LittleEndian\" header_type=\"UInt64\" \
         compressor=\"vtkZLibDataCompressor\"",
        &arr,
        Some(("raw", &cat(&h, &z))),
    );
    f.fields = (0..h.len() / 8)
        .map(|i| Field::int(f.text_len + 8 * i, 8, false))
        .collect();
    seeds.push(seed("appended raw zlib, UInt64 header", vec![f]));
    let other = b64(&cat(&4u32.to_le_bytes(), &[1, 2, 3, 4]));
    let (h, z) = vtk_zlib(&data, 32, false, false);
    let arr = format!("{ARRAY} format=\"appended\" offset=\"{}\"/>", other.len());
    let app = other + &b64(&h) + &b64(&z);
    seeds.push(seed(
        "appended base64 zlib",
        vec![vti(
            "a.vti",
            "byte_order=\"LittleEndian\" header_type=\"UInt32\" \
             compressor=\"vtkZLibDataCompressor\"",
            &arr,
            Some(("base64", app.as_bytes())),
        )],
    ));
    let enc = b64(&cat(&(data.len() as u32).to_le_bytes(), &data));
    let arr = format!("{ARRAY} format=\"appended\" offset=\"0\"/>");
    seeds.push(seed(
        "appended base64",
        vec![vti("a.vti", "", &arr, Some(("base64", enc.as_bytes())))],
    ));
    let enc = b64(&cat(&60u32.to_le_bytes(), &u8s()));
    let arr =
        format!("<DataArray type=\"UInt8\" Name=\"density\" format=\"binary\">{enc}</DataArray>");
    seeds.push(seed(
        "inline base64 uint8",
        vec![vti("a.vti", "", &arr, None)],
    ));
    seeds
}

// ---------------------------------------------------------------------------------------
// DICOM

struct Slice {
    series: &'static str,
    position: Option<[f64; 3]>,
    instance: i32,
    slope: f64,
    intercept: f64,
    signed: bool,
    bits: u16,
    pixels: Vec<u8>,
}

/// A 5×4 CT-like slice (rows 4, columns 5).
fn slice_spec(ts: &str, s: &Slice) -> Spec {
    let mut e = vec![
        Elem::str((0x0008, 0x0016), "UI", "1.2.840.10008.5.1.4.1.1.2"),
        Elem::str((0x0008, 0x0060), "CS", "CT"),
        Elem {
            tag: (0x0008, 0x1032),
            vr: *b"SQ",
            value: Value::Seq(vec![
                Elem::str((0x0008, 0x0100), "SH", "CODE"),
                Elem::str((0x0008, 0x0104), "LO", "meaning"),
            ]),
        },
        Elem::str((0x0018, 0x0050), "DS", "2.5"),
        Elem::str((0x0020, 0x000D), "UI", "1.2.3.4"),
        Elem::str((0x0020, 0x000E), "UI", s.series),
        Elem::str((0x0020, 0x0013), "IS", &s.instance.to_string()),
    ];
    if let Some(p) = s.position {
        e.push(Elem::str(
            (0x0020, 0x0032),
            "DS",
            &format!("{}\\{}\\{}", p[0], p[1], p[2]),
        ));
        e.push(Elem::str((0x0020, 0x0037), "DS", "1\\0\\0\\0\\1\\0"));
    }
    e.extend([
        Elem::us((0x0028, 0x0002), 1),
        Elem::str((0x0028, 0x0004), "CS", "MONOCHROME2"),
        Elem::us((0x0028, 0x0010), 4),
        Elem::us((0x0028, 0x0011), 5),
        Elem::str((0x0028, 0x0030), "DS", "0.75\\0.5"),
        Elem::us((0x0028, 0x0100), s.bits),
        Elem::us((0x0028, 0x0101), if s.bits == 16 { 12 } else { s.bits }),
        Elem::us((0x0028, 0x0102), if s.bits == 16 { 11 } else { s.bits - 1 }),
        Elem::us((0x0028, 0x0103), s.signed as u16),
        Elem::str((0x0028, 0x1052), "DS", &s.intercept.to_string()),
        Elem::str((0x0028, 0x1053), "DS", &s.slope.to_string()),
        Elem::bytes(
            (0x7FE0, 0x0010),
            if s.bits == 8 { "OB" } else { "OW" },
            s.pixels.clone(),
        ),
    ]);
    Spec {
        ts: ts.into(),
        elems: e,
    }
}

/// A 3-slice series, file names in reverse slice order, and a file that is not DICOM.
fn series(label: &str, ts: &str, signed: bool, bits: u16, positions: bool) -> Seed {
    let be = ts == dicom::EXPLICIT_BE;
    let mut files = Vec::new();
    for z in 0..3 {
        let pixels = match bits {
            8 => u8s()[z * 20..z * 20 + 20].to_vec(),
            _ => {
                let v = &u16s()[z * 20..z * 20 + 20];
                let v: Vec<u16> = v.iter().map(|x| x & 0x0fff).collect();
                if be {
                    be_u16(&v)
                } else {
                    le_u16(&v)
                }
            }
        };
        let s = Slice {
            series: "1.2.3.4.5",
            position: positions.then_some([-10.0, 20.0, 100.0 + 2.5 * z as f64]),
            instance: z as i32 + 1,
            slope: 1.0,
            intercept: if signed { -1024.0 } else { 0.0 },
            signed,
            bits,
            pixels,
        };
        let spec = slice_spec(ts, &s);
        let mut f = SeedFile::binary(&format!("IM{:04}.dcm", 9 - z), spec.to_bytes());
        f.dicom = Some(spec);
        files.push(f);
    }
    files.push(SeedFile::binary("README.txt", b"not a DICOM file".to_vec()).weight(0));
    Seed {
        label: label.into(),
        files,
        entry: None,
        raw: None,
    }
}

pub fn dicom_seeds() -> Vec<Seed> {
    vec![
        series(
            "implicit LE, signed, rescaled",
            dicom::IMPLICIT_LE,
            true,
            16,
            true,
        ),
        series("explicit LE, unsigned", dicom::EXPLICIT_LE, false, 16, true),
        series("explicit BE, signed", dicom::EXPLICIT_BE, true, 16, true),
        series("deflated explicit LE", dicom::DEFLATED_LE, false, 16, true),
        series(
            "explicit LE 8-bit, instance order",
            dicom::EXPLICIT_LE,
            false,
            8,
            false,
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// Transfer functions

pub fn transfer() -> Vec<Seed> {
    let mut seeds: Vec<Seed> = refrakt::transfer::PRESETS
        .iter()
        .filter(|(n, _)| ["ct-bone", "glass", "lung-ct", "wine-glass"].contains(n))
        .map(|(n, text)| seed(n, vec![SeedFile::text("tf.toml", text)]))
        .collect();
    seeds.push(seed(
        "all four functions with steps",
        vec![SeedFile::text(
            "tf.toml",
            "name = \"fuzz\"\ndescription = \"every function, a step in each\"\n\
             colour = [[0.0, 1.0, 0.5, 0.25], [0.5, 1.0, 0.5, 0.25], [0.5, 0.0, 1.0, 2.0], \
             [1.0, 0.0, 1.0, 2.0]]\n\
             opacity = [[0.0, 0.0], [0.3, 0.0], [0.3, 0.7], [1.0, 1.0]]\n\
             medium = [[0.0, 1.0, 1.0, 1.0], [0.6, 0.9, 0.2, 0.1], [0.6, 1.0, 1.0, 1.0]]\n\
             eta = [[0.0, 1.0], [0.5, 1.5], [1.0, 2.42]]\n",
        )],
    ));
    seeds
}

// ---------------------------------------------------------------------------------------
// Scene files

const FILES: &str = r#"
name = "files"
[volume]
file = "vol_5x4x3_uint8.raw"
spacing = [1.0, 1.0, 2.0]
window = [0.0, 200.0]
flip = "xy"
[transfer]
file = "tf.toml"
[camera]
azimuth = 30.0
elevation = 15.0
distance = 2.2
fov = 35.0
target = [0.1, 0.0, -0.1]
[light]
towards = [0.3, -1.0, 0.2]
colour = [1.0, 0.9, 0.8]
softness = 1.5
[environment]
map = "sky"
rotation = 45.0
[render]
model = "refract"
width = 64
height = 48
sample_distance = 0.5
preintegrated = true
roughness = 0.2
specular = 0.8
eta_scale = 1.0
light_transport = "forward"
light_rays = 2
clip = [1.0, 0.0, 0.0, 0.1]
exposure = 0.5
tonemap = "reinhard"
"#;

const RAW: &str = r#"
[volume]
file = "vol.bin"
dims = [5, 4, 3]
type = "u16"
upright = false
[transfer]
preset = "ct-bone"
[environment]
map = "env.exr"
[render]
model = "refract"
"#;

pub fn scene() -> Vec<Seed> {
    let aux = |name: &str, bytes: Vec<u8>| SeedFile::binary(name, bytes).weight(0);
    vec![
        seed(
            "builtin, inline transfer",
            vec![SeedFile::text("scene.toml", SMALL)],
        ),
        seed(
            "volume and transfer files, every section",
            vec![
                SeedFile::text("scene.toml", FILES),
                aux("vol_5x4x3_uint8.raw", u8s()),
                aux("tf.toml", b"opacity = [[0.0, 0.0], [1.0, 1.0]]\n".to_vec()),
            ],
        ),
        seed(
            "raw layout, preset, map file",
            vec![
                SeedFile::text("scene.toml", RAW),
                aux("vol.bin", le_u16(&u16s())),
                aux("env.exr", b"only its existence is checked".to_vec()),
            ],
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// Environment maps

/// A 16×8 map: a positive gradient.
fn pixel(x: usize, y: usize) -> [f32; 3] {
    [
        0.1 + x as f32 / 16.0,
        0.2 + y as f32 / 8.0,
        0.5 + ((x * y) % 5) as f32 / 10.0,
    ]
}

fn exr_file(encoding: exr::prelude::Encoding, half: bool) -> Vec<u8> {
    use exr::prelude::*;
    let mut out = std::io::Cursor::new(Vec::new());
    if half {
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = pixel(x, y);
            (
                f16::from_f32(p[0]),
                f16::from_f32(p[1]),
                f16::from_f32(p[2]),
            )
        });
        Image::from_encoded_channels((16, 8), encoding, channels)
            .write()
            .to_buffered(&mut out)
            .unwrap();
    } else {
        let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
            let p = pixel(x, y);
            (p[0], p[1], p[2], 1.0f32)
        });
        Image::from_encoded_channels((16, 8), encoding, channels)
            .write()
            .to_buffered(&mut out)
            .unwrap();
    }
    out.into_inner()
}

/// The numbers of an EXR header: attribute sizes, windows, channel types and sampling,
/// compression, tile sizes, and the first words of the offset table.
fn exr_fields(f: &[u8]) -> Vec<Field> {
    let mut fields = vec![Field::int(4, 4, false)];
    let mut at = 8;
    let cstr = |at: usize| -> Option<(String, usize)> {
        let end = at + f.get(at..)?.iter().position(|&b| b == 0)?;
        Some((String::from_utf8_lossy(&f[at..end]).into_owned(), end + 1))
    };
    while let Some((name, next)) = cstr(at) {
        if name.is_empty() {
            at = next;
            break;
        }
        let Some((ty, next)) = cstr(next) else { break };
        let size = i32::from_le_bytes(f[next..next + 4].try_into().unwrap()) as usize;
        fields.push(Field::int(next, 4, false));
        let v = next + 4;
        match ty.as_str() {
            "box2i" => fields.extend((0..4).map(|i| Field::int(v + 4 * i, 4, false))),
            "int" => fields.push(Field::int(v, 4, false)),
            "float" => fields.push(Field::float(v, false)),
            "v2f" => fields.extend((0..2).map(|i| Field::float(v + 4 * i, false))),
            "compression" | "lineOrder" => fields.push(Field::int(v, 1, false)),
            "tiledesc" => {
                fields.extend((0..2).map(|i| Field::int(v + 4 * i, 4, false)));
                fields.push(Field::int(v + 8, 1, false));
            }
            "chlist" => {
                let mut c = v;
                while let Some((ch, next)) = cstr(c) {
                    if ch.is_empty() || next + 16 > v + size {
                        break;
                    }
                    fields.push(Field::int(next, 4, false));
                    fields.push(Field::int(next + 8, 4, false));
                    fields.push(Field::int(next + 12, 4, false));
                    c = next + 16;
                }
            }
            _ => {}
        }
        at = v + size;
    }
    fields.extend((0..4).map(|i| Field::int(at + 8 * i, 8, false)));
    fields.retain(|x| x.at + x.width <= f.len());
    fields
}

fn png_file(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        let p = pixel(x as usize, y as usize);
        image::Rgb(p.map(|c| (c.min(1.0) * 255.0) as u8))
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn jpeg_file() -> Vec<u8> {
    let img = image::RgbImage::from_fn(16, 8, |x, y| {
        let p = pixel(x as usize, y as usize);
        image::Rgb(p.map(|c| (c.min(1.0) * 255.0) as u8))
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Jpeg).unwrap();
    out.into_inner()
}

/// Marker lengths and the frame header (precision, height, width, components) of a JPEG.
fn jpeg_fields(f: &[u8]) -> Vec<Field> {
    let mut fields = Vec::new();
    let mut at = 2;
    while at + 4 <= f.len() && f[at] == 0xFF {
        let marker = f[at + 1];
        let len = u16::from_be_bytes([f[at + 2], f[at + 3]]) as usize;
        fields.push(Field::int(at + 2, 2, true));
        if (0xC0..=0xC2).contains(&marker) {
            fields.push(Field::int(at + 4, 1, true));
            fields.push(Field::int(at + 5, 2, true));
            fields.push(Field::int(at + 7, 2, true));
            fields.push(Field::int(at + 9, 1, true));
        }
        if marker == 0xDA {
            break;
        }
        at += 2 + len;
    }
    fields
}

fn hdr_file() -> Vec<u8> {
    let img = image::Rgb32FImage::from_fn(16, 8, |x, y| image::Rgb(pixel(x as usize, y as usize)));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Hdr).unwrap();
    out.into_inner()
}

pub fn environment() -> Vec<Seed> {
    use exr::prelude::{Blocks, Compression as C, Encoding, LineOrder};
    let exr = |name: &str, bytes: Vec<u8>| {
        let fields = exr_fields(&bytes);
        seed(
            name,
            vec![SeedFile::binary("map.exr", bytes).fields(fields)],
        )
    };
    let scan = |compression| Encoding {
        compression,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let png = png_file(16, 8);
    let jpg = jpeg_file();
    let hdr = hdr_file();
    // The Radiance header ends after its resolution line.
    let hdr_text = hdr
        .windows(2)
        .position(|w| w == b"\n\n")
        .and_then(|i| {
            hdr[i + 2..]
                .iter()
                .position(|&b| b == b'\n')
                .map(|j| i + 3 + j)
        })
        .unwrap_or(0);
    vec![
        exr(
            "exr f32 rgba uncompressed",
            exr_file(Encoding::UNCOMPRESSED, false),
        ),
        exr(
            "exr f16 rgb rle tiles",
            exr_file(Encoding::FAST_LOSSLESS, true),
        ),
        exr(
            "exr f32 rgba zip",
            exr_file(Encoding::SMALL_LOSSLESS, false),
        ),
        exr("exr f16 rgb piz", exr_file(scan(C::PIZ), true)),
        exr("exr f16 rgb b44 (lossy)", exr_file(scan(C::B44), true)),
        seed(
            "png rgb8",
            vec![SeedFile::binary("map.png", png.clone())
                .post(Post::Png)
                .fields(vec![
                    Field::int(16, 4, true),
                    Field::int(20, 4, true),
                    Field::int(24, 1, true),
                    Field::int(25, 1, true),
                    Field::int(28, 1, true),
                    Field::int(33, 4, true),
                ])],
        ),
        seed(
            "jpeg",
            vec![SeedFile::binary("map.jpg", jpg.clone()).fields(jpeg_fields(&jpg))],
        ),
        seed(
            "radiance hdr",
            vec![SeedFile::header("map.hdr", hdr, hdr_text)],
        ),
    ]
}

//! DICOM files for `tests/fuzz.rs`, kept as a list of elements so that the mutator can
//! change a value (Rows, BitsStored, a position, the transfer syntax) and write the file
//! again with every length right: that reaches the series logic behind the element
//! parser, which byte mutations mostly stop at.

use std::io::Write;

use crate::mutate::{Rng, NUMBERS};

pub const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
pub const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
pub const DEFLATED_LE: &str = "1.2.840.10008.1.2.1.99";
pub const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";

/// Transfer syntaxes the mutator swaps in: the four the reader knows, compressed ones it
/// must refuse by name, and nonsense.
const SYNTAXES: &[&str] = &[
    IMPLICIT_LE,
    EXPLICIT_LE,
    DEFLATED_LE,
    EXPLICIT_BE,
    "1.2.840.10008.1.2.4.70",
    "1.2.840.10008.1.2.5",
    "1.2.3",
    "",
];

#[derive(Clone, Debug)]
pub enum Value {
    Bytes(Vec<u8>),
    /// US (unsigned 16-bit), in the dataset's byte order.
    Us(u16),
    /// A sequence of undefined length with one item of undefined length.
    Seq(Vec<Elem>),
}

#[derive(Clone, Debug)]
pub struct Elem {
    pub tag: (u16, u16),
    pub vr: [u8; 2],
    pub value: Value,
}

impl Elem {
    pub fn str(tag: (u16, u16), vr: &str, s: &str) -> Elem {
        Elem {
            tag,
            vr: vr.as_bytes().try_into().unwrap(),
            value: Value::Bytes(s.as_bytes().to_vec()),
        }
    }
    pub fn us(tag: (u16, u16), v: u16) -> Elem {
        Elem {
            tag,
            vr: *b"US",
            value: Value::Us(v),
        }
    }
    pub fn bytes(tag: (u16, u16), vr: &str, v: Vec<u8>) -> Elem {
        Elem {
            tag,
            vr: vr.as_bytes().try_into().unwrap(),
            value: Value::Bytes(v),
        }
    }
}

/// One file: a Part-10 header (preamble, `DICM`, meta group) naming `ts`, then `elems`.
#[derive(Clone, Debug)]
pub struct Spec {
    pub ts: String,
    pub elems: Vec<Elem>,
}

struct Writer {
    explicit: bool,
    be: bool,
    out: Vec<u8>,
}

impl Writer {
    fn u16(&mut self, v: u16) {
        let b = if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
    }
    fn u32(&mut self, v: u32) {
        let b = if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.out.extend_from_slice(&b);
    }
    fn header(&mut self, tag: (u16, u16), vr: [u8; 2], len: u32) {
        self.u16(tag.0);
        self.u16(tag.1);
        if self.explicit {
            self.out.extend_from_slice(&vr);
            if matches!(&vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
                self.out.extend_from_slice(&[0, 0]);
                self.u32(len);
            } else {
                self.u16(len as u16);
            }
        } else {
            self.u32(len);
        }
    }
    fn elem(&mut self, e: &Elem) {
        match &e.value {
            Value::Bytes(v) => {
                let mut v = v.clone();
                if v.len() % 2 == 1 {
                    v.push(if matches!(&e.vr, b"UI" | b"OB") {
                        0
                    } else {
                        b' '
                    });
                }
                self.header(e.tag, e.vr, v.len() as u32);
                self.out.extend_from_slice(&v);
            }
            Value::Us(x) => {
                self.header(e.tag, e.vr, 2);
                self.u16(*x);
            }
            Value::Seq(items) => {
                self.header(e.tag, *b"SQ", u32::MAX);
                self.u16(0xFFFE);
                self.u16(0xE000);
                self.u32(u32::MAX);
                for i in items {
                    self.elem(i);
                }
                for t in [(0xFFFE, 0xE00D), (0xFFFE, 0xE0DD)] {
                    self.u16(t.0);
                    self.u16(t.1);
                    self.u32(0);
                }
            }
        }
    }
}

impl Spec {
    pub fn to_bytes(&self) -> Vec<u8> {
        let ts = self.ts.as_str();
        let mut meta = Writer {
            explicit: true,
            be: false,
            out: Vec::new(),
        };
        meta.elem(&Elem::bytes((0x0002, 0x0001), "OB", vec![0, 1]));
        meta.elem(&Elem::str(
            (0x0002, 0x0002),
            "UI",
            "1.2.840.10008.5.1.4.1.1.2",
        ));
        meta.elem(&Elem::str((0x0002, 0x0010), "UI", ts));
        let mut group = Writer {
            explicit: true,
            be: false,
            out: Vec::new(),
        };
        group.elem(&Elem::bytes(
            (0x0002, 0x0000),
            "UL",
            (meta.out.len() as u32).to_le_bytes().to_vec(),
        ));
        let mut body = Writer {
            explicit: ts != IMPLICIT_LE,
            be: ts == EXPLICIT_BE,
            out: Vec::new(),
        };
        for e in &self.elems {
            body.elem(e);
        }
        let mut f = vec![0u8; 128];
        f.extend_from_slice(b"DICM");
        f.extend_from_slice(&group.out);
        f.extend_from_slice(&meta.out);
        if ts == DEFLATED_LE {
            let mut e = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::fast());
            e.write_all(&body.out).unwrap();
            f.extend(e.finish().unwrap());
        } else {
            f.extend_from_slice(&body.out);
        }
        f
    }

    /// Changes one to three values (or elements) and returns the file.
    pub fn mutate(&self, rng: &mut Rng) -> Vec<u8> {
        let mut s = self.clone();
        for _ in 0..rng.range(1, 3) {
            if s.elems.is_empty() {
                break;
            }
            let i = rng.below(s.elems.len());
            match rng.below(12) {
                0 => s.ts = rng.pick(SYNTAXES).to_string(),
                1 => {
                    s.elems.remove(i);
                }
                2 => {
                    let e = s.elems[i].clone();
                    s.elems.insert(rng.below(s.elems.len() + 1), e);
                }
                3 => s.elems[i].vr = *rng.pick(&[*b"SQ", *b"UN", *b"OB", *b"US", *b"DS", *b"xx"]),
                4 => {
                    let j = rng.below(s.elems.len());
                    s.elems.swap(i, j);
                }
                _ => mutate_value(rng, &mut s.elems[i].value),
            }
        }
        s.to_bytes()
    }
}

fn mutate_value(rng: &mut Rng, v: &mut Value) {
    match v {
        Value::Us(x) => {
            *x = *rng.pick(&[
                0u16, 1, 2, 3, 4, 5, 7, 8, 9, 11, 12, 15, 16, 17, 31, 32, 33, 64, 0x7fff, 0x8000,
                0xffff,
            ])
        }
        Value::Seq(items) => {
            if rng.one_in(2) {
                items.clear();
            } else if let Some(e) = items.first().cloned() {
                // Nest the sequence in itself: depth beyond the reader's limit.
                *v = Value::Seq(vec![Elem {
                    tag: (0x0008, 0x1032),
                    vr: *b"SQ",
                    value: Value::Seq((0..rng.range(1, 40)).map(|_| e.clone()).collect()),
                }]);
            }
        }
        Value::Bytes(b) => {
            let text = b.iter().all(|c| c.is_ascii_graphic() || *c == b' ');
            if text && !b.is_empty() && !rng.one_in(4) {
                // A multi-valued number: replace one component.
                let s = String::from_utf8_lossy(b).into_owned();
                let mut parts: Vec<String> = s.split('\\').map(String::from).collect();
                let k = rng.below(parts.len());
                parts[k] = rng.pick(NUMBERS).to_string();
                if rng.one_in(6) {
                    parts.push("1".into());
                }
                *b = parts.join("\\").into_bytes();
            } else {
                // Pixel data (or anything): another length.
                let n = b.len();
                let new = match rng.below(5) {
                    0 => 0,
                    1 => n.saturating_sub(1),
                    2 => n + 1,
                    3 => n * 2,
                    _ => n / 2,
                };
                b.resize(new, 0x5a);
            }
        }
    }
}

//! The deterministic mutator of `tests/fuzz.rs`: a SplitMix64 generator and mutations of
//! seed files at the level of bits and bytes, lines and header fields, numbers and words.
//! Everything is a function of the case seed, so a case replays exactly.

/// SplitMix64 (Steele, Lea, Flood 2014): small, fast, and good enough to pick mutations.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    /// Uniform in `lo..=hi`.
    pub fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.below(hi - lo + 1)
    }

    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The seed of case `i` of a run whose base seed is `base`.
pub fn case_seed(base: u64, i: u64) -> u64 {
    Rng::new(base ^ i.wrapping_mul(0xD6E8_FEB8_6659_FD93)).next()
}

/// FNV-1a, to give every target its own stream of cases.
pub fn hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A number in a binary header: `width` bytes at `at`.
#[derive(Clone, Copy, Debug)]
pub struct Field {
    pub at: usize,
    pub width: usize,
    pub be: bool,
    pub float: bool,
}

impl Field {
    pub fn int(at: usize, width: usize, be: bool) -> Self {
        Field {
            at,
            width,
            be,
            float: false,
        }
    }
    pub fn float(at: usize, be: bool) -> Self {
        Field {
            at,
            width: 4,
            be,
            float: true,
        }
    }
}

/// What a mutation may borrow from elsewhere: the other seed files of the same target
/// (bytes and the length of their text header) and the words found in their headers.
pub struct Donors<'a> {
    pub files: Vec<(&'a [u8], usize)>,
    pub words: Vec<Vec<u8>>,
}

/// Numbers that break parsers: zero, signs, the edges of 16/32/64 bits, overflow, the
/// device limit, NaN and infinities, and a few malformed ones.
pub const NUMBERS: &[&str] = &[
    "0",
    "1",
    "-1",
    "2",
    "-0",
    "3",
    "4",
    "2048",
    "2049",
    "65535",
    "65536",
    "100000",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999999999",
    "1e308",
    "1e309",
    "-1e309",
    "1e-320",
    "1e38",
    "3.5e38",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "0.0",
    "0.5",
    "1.5",
    "-0.5",
    "+5",
    "0x10",
    "",
    "1.",
    ".",
    "-",
    "1e",
];

const BYTES: &[u8] = b"\x00\x01\x7f\x80\xff09-\n\r \"'<>=_./\\\t";
const RUNS: &[u8] = b"[{<(\"'\n0 ,=-_\\#";
const INTS16: &[u64] = &[
    0, 1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 32, 64, 256, 512, 768, 2049, 0x7fff, 0x8000, 0xfffe,
    0xffff,
];
const INTS32: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    120,
    348,
    352,
    540,
    2048,
    2049,
    0x10000,
    0x10001,
    1 << 24,
    1 << 30,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fffe,
    0xffff_ffff,
];
const INTS64: &[u64] = &[
    0,
    1,
    120,
    1 << 32,
    1 << 40,
    1 << 62,
    i64::MAX as u64,
    u64::MAX - 1,
    u64::MAX,
];
const FLOATS: &[f32] = &[
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    0.0,
    -0.0,
    -1.0,
    1.0,
    0.5,
    1e-40,
    1e-30,
    1e30,
    3.4e38,
    348.0,
    352.0,
    352.5,
    2049.0,
    1e9,
    4294967296.0,
];

/// Mutates `seed` (whose first `text_len` bytes are a text header, and whose binary header
/// numbers are `fields`) with one to eight stacked mutations.
pub fn mutate(
    rng: &mut Rng,
    seed: &[u8],
    text_len: usize,
    fields: &[Field],
    donors: &Donors,
) -> Vec<u8> {
    let mut m = Mutation {
        bytes: seed.to_vec(),
        text: text_len.min(seed.len()),
        fields,
        loose: false,
    };
    let n = if rng.one_in(6) {
        rng.range(2, 8)
    } else {
        rng.range(1, 2)
    };
    for _ in 0..n {
        // Text headers get mostly text mutations, binary files byte and field mutations.
        for _ in 0..32 {
            let text_op = m.text > 0 && !rng.one_in(3);
            let done = if text_op {
                match rng.below(10) {
                    0..=3 => m.replace_number(rng),
                    4..=6 => m.line(rng, donors),
                    _ => m.replace_word(rng, donors),
                }
            } else {
                match rng.below(if fields.is_empty() { 11 } else { 14 }) {
                    0 | 1 => m.flip_bit(rng),
                    2 => m.set_byte(rng),
                    3 => m.insert_bytes(rng),
                    4 => m.delete_range(rng),
                    5 => m.truncate(rng),
                    6 => m.duplicate_block(rng),
                    7 => m.splice(rng, donors),
                    8 => m.run(rng),
                    9 | 10 => m.write_word(rng),
                    _ => m.replace_field(rng),
                }
            };
            if done {
                break;
            }
        }
    }
    m.bytes
}

/// Replaces the numbers of a file name (a raw file's layout) or one of its words.
pub fn mutate_name(rng: &mut Rng, name: &str, donors: &Donors) -> String {
    let fields = [];
    let mut m = Mutation {
        bytes: name.as_bytes().to_vec(),
        text: name.len(),
        fields: &fields,
        loose: true,
    };
    for _ in 0..8 {
        let done = if rng.one_in(4) {
            m.replace_word(rng, donors)
        } else {
            m.replace_number(rng)
        };
        if done {
            break;
        }
    }
    let s: String = String::from_utf8_lossy(&m.bytes)
        .chars()
        .filter(|c| *c != '/' && *c != '\0')
        .take(200)
        .collect();
    if s.is_empty() || s == "." || s == ".." {
        name.to_string()
    } else {
        s
    }
}

struct Mutation<'a> {
    bytes: Vec<u8>,
    /// End of the text header (kept up to date through insertions and deletions).
    text: usize,
    fields: &'a [Field],
    /// Numbers inside words count too (`a_5x4x3_int16.raw`).
    loose: bool,
}

impl Mutation<'_> {
    /// Replaces `at..at + removed` by `new`, keeping the text header's end in step.
    fn splice_at(&mut self, at: usize, removed: usize, new: &[u8]) {
        let at = at.min(self.bytes.len());
        let end = (at + removed).min(self.bytes.len());
        if at < self.text {
            self.text = self.text - (end.min(self.text) - at) + new.len();
        }
        self.bytes.splice(at..end, new.iter().copied());
        self.text = self.text.min(self.bytes.len());
    }

    fn pos(&self, rng: &mut Rng) -> usize {
        // Headers are at the start: favour the first 512 bytes.
        if rng.one_in(2) {
            rng.below(self.bytes.len().min(512) + 1)
        } else {
            rng.below(self.bytes.len() + 1)
        }
    }

    fn flip_bit(&mut self, rng: &mut Rng) -> bool {
        if self.bytes.is_empty() {
            return false;
        }
        let i = self.pos(rng).min(self.bytes.len() - 1);
        self.bytes[i] ^= 1 << rng.below(8);
        true
    }

    fn set_byte(&mut self, rng: &mut Rng) -> bool {
        if self.bytes.is_empty() {
            return false;
        }
        let i = self.pos(rng).min(self.bytes.len() - 1);
        self.bytes[i] = if rng.one_in(4) {
            rng.next() as u8
        } else {
            *rng.pick(BYTES)
        };
        true
    }

    fn insert_bytes(&mut self, rng: &mut Rng) -> bool {
        let n = rng.range(1, 16);
        let new: Vec<u8> = (0..n)
            .map(|_| {
                if rng.one_in(2) {
                    rng.next() as u8
                } else {
                    *rng.pick(BYTES)
                }
            })
            .collect();
        let at = self.pos(rng);
        self.splice_at(at, 0, &new);
        true
    }

    fn delete_range(&mut self, rng: &mut Rng) -> bool {
        if self.bytes.is_empty() {
            return false;
        }
        let at = self.pos(rng).min(self.bytes.len() - 1);
        let n = if rng.one_in(4) {
            rng.range(1, 256)
        } else {
            rng.range(1, 8)
        };
        self.splice_at(at, n, &[]);
        true
    }

    fn truncate(&mut self, rng: &mut Rng) -> bool {
        if self.bytes.is_empty() {
            return false;
        }
        let at = rng.below(self.bytes.len());
        self.bytes.truncate(at);
        self.text = self.text.min(at);
        true
    }

    fn duplicate_block(&mut self, rng: &mut Rng) -> bool {
        if self.bytes.is_empty() {
            return false;
        }
        let from = rng.below(self.bytes.len());
        let n = rng.range(1, 64).min(self.bytes.len() - from);
        let block = self.bytes[from..from + n].to_vec();
        let at = self.pos(rng);
        self.splice_at(at, 0, &block);
        true
    }

    /// A prefix of this file, then a suffix of another seed file of the same target.
    fn splice(&mut self, rng: &mut Rng, donors: &Donors) -> bool {
        if donors.files.is_empty() {
            return false;
        }
        let (other, _) = *rng.pick(&donors.files);
        let cut = rng.below(self.bytes.len() + 1);
        let from = rng.below(other.len() + 1);
        let removed = self.bytes.len() - cut;
        self.splice_at(cut, removed, &other[from..]);
        true
    }

    /// A run of one character: deep nesting, long lines, many separators.
    fn run(&mut self, rng: &mut Rng) -> bool {
        let c = if rng.one_in(4) {
            rng.next() as u8
        } else {
            *rng.pick(RUNS)
        };
        let n = if rng.one_in(8) {
            rng.range(1000, 5000)
        } else {
            rng.range(1, 64)
        };
        let at = self.pos(rng);
        self.splice_at(at, 0, &vec![c; n]);
        true
    }

    /// An interesting 2-, 4- or 8-byte integer anywhere (mostly near the start).
    fn write_word(&mut self, rng: &mut Rng) -> bool {
        let width = *rng.pick(&[2usize, 4, 4, 8]);
        if self.bytes.len() < width {
            return false;
        }
        let at = self.pos(rng).min(self.bytes.len() - width);
        let f = Field::int(at, width, rng.one_in(2));
        self.write_field(rng, f);
        true
    }

    fn replace_field(&mut self, rng: &mut Rng) -> bool {
        let f = *rng.pick(self.fields);
        if f.at + f.width > self.bytes.len() {
            return false;
        }
        self.write_field(rng, f);
        true
    }

    fn write_field(&mut self, rng: &mut Rng, f: Field) {
        let slot = &mut self.bytes[f.at..f.at + f.width];
        let read = |s: &[u8]| {
            let mut v = 0u64;
            for i in 0..s.len() {
                let b = if f.be { s[i] } else { s[s.len() - 1 - i] };
                v = (v << 8) | b as u64;
            }
            v
        };
        let value: u64 = if f.float && rng.one_in(3) {
            // A nearby float: off by one, doubled, negated.
            let old = f32::from_bits(read(slot) as u32);
            let new = match rng.below(4) {
                0 => old + 1.0,
                1 => old * 2.0,
                2 => -old,
                _ => old * 1e6,
            };
            new.to_bits() as u64
        } else if f.float {
            rng.pick(FLOATS).to_bits() as u64
        } else if rng.one_in(3) {
            // A nearby integer.
            let old = read(slot);
            match rng.below(4) {
                0 => old.wrapping_add(1),
                1 => old.wrapping_sub(1),
                2 => old.wrapping_mul(2),
                _ => old.wrapping_mul(256),
            }
        } else {
            match f.width {
                1 => *rng.pick(&[0u64, 1, 2, 3, 7, 8, 0x7f, 0x80, 0xff]),
                2 => *rng.pick(INTS16),
                4 => *rng.pick(INTS32),
                _ => *rng.pick(INTS64),
            }
        };
        for i in 0..f.width {
            let b = (value >> (8 * i)) as u8;
            if f.be {
                slot[f.width - 1 - i] = b;
            } else {
                slot[i] = b;
            }
        }
    }

    /// Replaces a number of the text header: an interesting value, or a nearby one.
    fn replace_number(&mut self, rng: &mut Rng) -> bool {
        let numbers = numbers(&self.bytes[..self.text], self.loose);
        if numbers.is_empty() {
            return false;
        }
        let (a, b) = *rng.pick(&numbers);
        let old = String::from_utf8_lossy(&self.bytes[a..b]).into_owned();
        let new = match old.parse::<i128>() {
            Ok(v) if rng.one_in(3) => match rng.below(5) {
                0 => v.saturating_add(1).to_string(),
                1 => v.saturating_sub(1).to_string(),
                2 => v.saturating_neg().to_string(),
                3 => v.saturating_mul(1000).to_string(),
                _ => v.saturating_mul(v).saturating_mul(v).to_string(),
            },
            _ => rng.pick(NUMBERS).to_string(),
        };
        self.splice_at(a, b - a, new.as_bytes());
        true
    }

    /// Deletes, duplicates (the same field twice), moves or swaps a header line, or puts
    /// in a line of another seed's header.
    fn line(&mut self, rng: &mut Rng, donors: &Donors) -> bool {
        let mine = lines(&self.bytes[..self.text]);
        if mine.is_empty() {
            return false;
        }
        let (a, b) = *rng.pick(&mine);
        let line = self.bytes[a..b].to_vec();
        match rng.below(5) {
            0 => self.splice_at(a, b - a, &[]),
            1 => self.splice_at(b, 0, &line),
            2 => {
                let (c, _) = *rng.pick(&mine);
                self.splice_at(c, 0, &line);
            }
            3 => {
                let (c, d) = *rng.pick(&mine);
                if (c, d) == (a, b) {
                    return false;
                }
                let other = self.bytes[c..d].to_vec();
                // Replace the later one first so the earlier offsets stay right.
                let ((p, q, x), (r, s, y)) = if a < c {
                    ((c, d, &line), (a, b, &other))
                } else {
                    ((a, b, &other), (c, d, &line))
                };
                self.splice_at(p, q - p, x);
                self.splice_at(r, s - r, y);
            }
            _ => {
                let texts: Vec<&(&[u8], usize)> =
                    donors.files.iter().filter(|(_, t)| *t > 0).collect();
                if texts.is_empty() {
                    return false;
                }
                let (other, t) = **rng.pick(&texts);
                let their = lines(&other[..t.min(other.len())]);
                if their.is_empty() {
                    return false;
                }
                let (c, d) = *rng.pick(&their);
                let new = other[c..d].to_vec();
                let (at, _) = *rng.pick(&mine);
                self.splice_at(at, 0, &new);
            }
        }
        true
    }

    /// Replaces a word of the text header by a word from any seed of the target (`raw`
    /// by `gzip`, `LOCAL` by a file name, `UInt32` by `Float64` …), or drops it.
    fn replace_word(&mut self, rng: &mut Rng, donors: &Donors) -> bool {
        let words = words(&self.bytes[..self.text]);
        if words.is_empty() || donors.words.is_empty() {
            return false;
        }
        let (a, b) = *rng.pick(&words);
        let new = match rng.below(8) {
            0 => Vec::new(),
            1 => self.bytes[a..b].to_ascii_uppercase(),
            _ => rng.pick(&donors.words).clone(),
        };
        self.splice_at(a, b - a, &new);
        true
    }
}

/// Spans of decimal numbers (with sign, fraction and exponent); `loose`: also those that
/// follow a letter.
fn numbers(s: &[u8], loose: bool) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() && out.len() < 4096 {
        let starts = s[i].is_ascii_digit()
            || (matches!(s[i], b'-' | b'+' | b'.')
                && s.get(i + 1).is_some_and(|c| c.is_ascii_digit()));
        // Not in the middle of a word (`uint16`, `NRRD0004`).
        let in_word = !loose && i > 0 && (s[i - 1].is_ascii_alphanumeric() || s[i - 1] == b'_');
        if !starts || (in_word && !matches!(s[i], b'-' | b'+')) {
            i += 1;
            continue;
        }
        let a = i;
        i += 1;
        while i < s.len() {
            let c = s[i];
            let exp_sign = matches!(c, b'-' | b'+') && matches!(s[i - 1], b'e' | b'E');
            let exp = matches!(c, b'e' | b'E')
                && s.get(i + 1)
                    .is_some_and(|n| n.is_ascii_digit() || matches!(n, b'-' | b'+'));
            if c.is_ascii_digit() || c == b'.' || exp || exp_sign {
                i += 1;
            } else {
                break;
            }
        }
        out.push((a, i));
    }
    out
}

/// Spans of lines, each with its line end.
fn lines(s: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut a = 0;
    for (i, &c) in s.iter().enumerate() {
        if c == b'\n' {
            out.push((a, i + 1));
            a = i + 1;
        }
    }
    if a < s.len() {
        out.push((a, s.len()));
    }
    out
}

/// Spans of identifier-like words of at least two characters.
pub fn words(s: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        if s[i].is_ascii_alphabetic() {
            let a = i;
            while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
                i += 1;
            }
            if i - a >= 2 {
                out.push((a, i));
            }
        } else {
            i += 1;
        }
    }
    out
}

/// CRC-32 (IEEE), to repair PNG chunk checksums after a mutation.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Recomputes the checksum of every complete PNG chunk, so that mutations inside the
/// chunks reach the decoder instead of stopping at the CRC check.
pub fn fix_png_crcs(png: &mut [u8]) {
    let mut at = 8;
    while at + 12 <= png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
        let Some(end) = (at + 8).checked_add(len).filter(|e| e + 4 <= png.len()) else {
            break;
        };
        let crc = crc32(&png[at + 4..end]);
        png[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans() {
        let s = b"sizes: 5 4 3\nspacing: -1.5e3 .5\nNRRD0004 uint16\n";
        let n: Vec<&[u8]> = numbers(s, false).iter().map(|&(a, b)| &s[a..b]).collect();
        assert_eq!(
            n,
            [&b"5"[..], b"4", b"3", b"-1.5e3", b".5"],
            "{:?}",
            n.iter()
                .map(|x| String::from_utf8_lossy(x))
                .collect::<Vec<_>>()
        );
        assert_eq!(numbers(b"a_5x4x3_int16.raw", true).len(), 4);
        assert_eq!(lines(b"a\nb\nc").len(), 3);
        assert_eq!(words(b"x ab_1 cd").len(), 2);
        assert_eq!(crc32(b"IEND"), 0xAE42_6082);
    }
}

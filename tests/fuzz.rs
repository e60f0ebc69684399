//! Issue 15: a fuzz harness for every file parser, on stable Rust, with no new dependency.
//!
//! Each parser gets valid seed files of its format (built in `tests/fuzz/seeds.rs`: raw,
//! NRRD attached and detached, NIfTI `.nii`/`.nii.gz`, MetaImage `.mha`/`.mhd`, VTI in
//! every encoding, DICOM series, transfer-function TOML, scene TOML, EXR/HDR/PNG/JPEG
//! environment maps). Every case mutates one seed with a seeded, deterministic mutator
//! (`tests/fuzz/mutate.rs`: bit flips, byte insertions and deletions, truncation, splicing
//! with other seeds, header lines deleted, duplicated or moved, header numbers replaced by
//! huge, negative, NaN or zero values, words swapped, binary header fields rewritten, PNG
//! checksums repaired, DICOM elements changed and re-encoded), writes it to a temporary
//! directory and calls the parser:
//!
//! - `refrakt::volume::formats::load_volume` (most cases with
//!   `DeviceLimits { max_3d_extent: 2048, bytes_available: 256 MiB }`, some with a device
//!   too small for the seeds, some without limits, some with a window or a mutated raw
//!   layout),
//! - `refrakt::transfer::TransferFunctions::load`, `refrakt::scene::Scene::load`,
//!   `refrakt::environment::EnvironmentMap::load`.
//!
//! A case fails when the call panics (caught with `catch_unwind`), when it breaks the
//! parser's contract (a volume accepted beyond the limits it was given, an accepted value
//! out of range, a volume error on several lines or not naming the file), or when it
//! allocates too much: a counting `#[global_allocator]` records the largest single
//! allocation and the peak of live bytes of every call, and neither may exceed
//! 64 MiB + 64 × the bytes of the input files. (A header that claims a huge volume must
//! be refused before anything of that size is allocated.) Compressed images legitimately
//! expand more: for environment maps the bound is 64 MiB + 4096 × the file's bytes (what
//! `EnvironmentMap::load` allows a file), twice that for the peak. A failing case prints
//! its case seed, what it was given and how to replay it, and its input files are kept
//! under `target/tmp/fuzz-failures/`. A panic inside a dependency that the parser catches
//! and returns as an error is not a failure, but it is counted and printed.
//!
//! The seeds themselves must load, and the counts printed per parser (executions,
//! accepted, refused, crashes) must show that some mutated inputs were refused and some
//! accepted, or the test fails: a broken mutator or parser cannot pass unnoticed.
//!
//! # Budget
//!
//! CI runs [`DEFAULT_ITERS`] cases per parser (a few seconds for the whole file, in debug
//! mode). The environment changes that:
//!
//! - `REFRAKT_FUZZ_ITERS=<n>`: cases per parser. The developers' long run, e.g.
//!   `REFRAKT_FUZZ_ITERS=100000 cargo test --release --test fuzz -- --nocapture`
//!   (between 15 s and a minute and a half per parser on two cores).
//! - `REFRAKT_FUZZ_SEED=<u64>`: a different base seed, i.e. other cases (default 0).
//! - `REFRAKT_FUZZ_SEEDS=<text>`: only the seed files whose label contains it (e.g.
//!   `exr`, `gzip`, `DICOM`), to dwell on one format or encoding.
//! - `REFRAKT_FUZZ_REPLAY=<parser>:<case seed>`: runs that one case of that parser (the
//!   line a failure prints), says what happened and keeps its input under
//!   `target/tmp/fuzz-replay/`.
//!
//! Tests of this file run one after another (they share the allocation counters); no GPU
//! and no Vulkan context are involved.

#[path = "fuzz/dicom.rs"]
mod dicom;
#[path = "fuzz/mutate.rs"]
mod mutate;
#[path = "fuzz/seeds.rs"]
mod seeds;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::{Cell, RefCell};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicIsize, AtomicU64, AtomicUsize, Ordering::Relaxed};
use std::sync::{Mutex, Once, PoisonError};
use std::time::Instant;

use refrakt::environment::EnvironmentMap;
use refrakt::scene::Scene;
use refrakt::transfer::{TransferFunctions, MAX_ETA, MIN_ETA};
use refrakt::volume::formats::{
    check_volume_limits, load_volume, DeviceLimits, LoadOptions, ScalarKind,
};

use mutate::{case_seed, hash, mutate, mutate_name, Donors, Rng};
use seeds::{Post, Seed};

/// Cases per parser in CI (`REFRAKT_FUZZ_ITERS` overrides it).
pub const DEFAULT_ITERS: u64 = 1000;

/// What most cases pass as the device: a common `maxImageDimension3D` and a small heap.
const LIMITS: DeviceLimits = DeviceLimits {
    max_3d_extent: 2048,
    bytes_available: Some(256 << 20),
};
/// A device too small for every seed (5×4×3 voxels): all must be refused.
const TINY: DeviceLimits = DeviceLimits {
    max_3d_extent: 4,
    bytes_available: Some(1 << 20),
};

/// Allowed allocation per call: this much plus [`PER_INPUT_BYTE`] × the input's bytes.
const FIXED_BYTES: usize = 64 << 20;
const PER_INPUT_BYTE: usize = 64;
/// Compressed images legitimately expand far more (deflate up to 1032:1, then widened to
/// f32 RGBA): an environment map's pixel buffer may take what `EnvironmentMap::load`
/// allows its file (64 MiB + 4096 × its bytes), and the decoder's own block buffers may
/// come on top (peak: twice that).
const PER_INPUT_BYTE_IMAGE: usize = 4096;

// ---------------------------------------------------------------------------------------
// Counting allocator

/// Wraps the system allocator and counts live bytes, their peak and the largest single
/// request while a call is measured ([`measured`]).
struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);
static LARGEST: AtomicUsize = AtomicUsize::new(0);
static ARMED: AtomicBool = AtomicBool::new(false);
/// The case being measured, for the message of a refused request.
static CASE_SEED: AtomicU64 = AtomicU64::new(0);
static CASE_NAME: Mutex<&str> = Mutex::new("");

/// A request this large during a measured call is refused (the process then aborts with
/// "memory allocation failed") rather than risking the machine; the case is named first.
const HARD_CAP: usize = 1 << 30;

#[global_allocator]
static ALLOCATOR: Counting = Counting;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !admit(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = System.alloc(layout);
        if !p.is_null() {
            grew(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !admit(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = System.alloc_zeroed(layout);
        if !p.is_null() {
            grew(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        LIVE.fetch_sub(layout.size() as isize, Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if !admit(new_size) {
            return std::ptr::null_mut();
        }
        let p = System.realloc(ptr, layout, new_size);
        if !p.is_null() {
            grew(new_size as isize - layout.size() as isize);
        }
        p
    }
}

fn admit(size: usize) -> bool {
    if !ARMED.load(Relaxed) {
        return true;
    }
    LARGEST.fetch_max(size, Relaxed);
    if size <= HARD_CAP {
        return true;
    }
    // Say which case it was without allocating: format on the stack, write to fd 2.
    struct Buf([u8; 256], usize);
    impl std::fmt::Write for Buf {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            let n = s.len().min(self.0.len() - self.1);
            self.0[self.1..self.1 + n].copy_from_slice(&s.as_bytes()[..n]);
            self.1 += n;
            Ok(())
        }
    }
    let mut b = Buf([0; 256], 0);
    let name = CASE_NAME.try_lock().map(|n| *n).unwrap_or("?");
    let _ = std::fmt::write(
        &mut b,
        format_args!(
            "\nfuzz: {name} case {:#018x} requested {size} bytes in one allocation; replay with \
             REFRAKT_FUZZ_REPLAY={name}:{:#x}\n",
            CASE_SEED.load(Relaxed),
            CASE_SEED.load(Relaxed)
        ),
    );
    let _ = std::io::Write::write_all(&mut std::io::stderr(), &b.0[..b.1]);
    false
}

fn grew(delta: isize) {
    let now = LIVE.fetch_add(delta, Relaxed) + delta;
    PEAK.fetch_max(now, Relaxed);
}

#[derive(Clone, Copy, Debug, Default)]
struct Usage {
    /// The largest single allocation (or reallocation) requested.
    largest: usize,
    /// The most bytes live at once beyond those live before the call.
    peak: usize,
}

fn measured<T>(f: impl FnOnce() -> T) -> (T, Usage) {
    LARGEST.store(0, Relaxed);
    let base = LIVE.load(Relaxed);
    PEAK.store(base, Relaxed);
    ARMED.store(true, Relaxed);
    let r = f();
    ARMED.store(false, Relaxed);
    let usage = Usage {
        largest: LARGEST.load(Relaxed),
        peak: (PEAK.load(Relaxed) - base).max(0) as usize,
    };
    (r, usage)
}

/// The tests of this file share the counters: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

// ---------------------------------------------------------------------------------------
// Panics

thread_local! {
    static IN_CASE: Cell<bool> = const { Cell::new(false) };
    static PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Panics inside a case are recorded (message and location) instead of printed; others go
/// to the default hook.
fn record_panics_in_cases() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let default = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if IN_CASE.with(Cell::get) {
                let at = info
                    .location()
                    .map(|l| format!(" at {}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                let msg = payload_text(info.payload());
                PANIC.with(|p| *p.borrow_mut() = Some(format!("panic '{msg}'{at}")));
            } else {
                default(info)
            }
        }));
    });
}

fn payload_text(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(not a string)".into()
    }
}

// ---------------------------------------------------------------------------------------
// Targets and cases

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Volume,
    Transfer,
    Scene,
    Environment,
}

struct Target {
    name: &'static str,
    kind: Kind,
    seeds: Vec<Seed>,
}

/// One input: the files to write (name, bytes), which one the parser gets (`None`: the
/// directory) and the options.
struct Case {
    seed: usize,
    files: Vec<(String, Vec<u8>)>,
    entry: Option<usize>,
    opts: LoadOptions,
}

enum Verdict {
    Accepted,
    Refused(String),
    /// Returned, but broke the parser's contract.
    Violation(String),
    Crash(String),
}

struct Outcome {
    verdict: Verdict,
    /// A panic the parser caught itself (and turned into an error).
    caught: Option<String>,
    usage: Usage,
    input_bytes: usize,
    kind: Kind,
}

impl Outcome {
    /// The bounds on the largest single allocation and on the peak of live bytes.
    fn bounds(&self) -> (usize, usize) {
        match self.kind {
            Kind::Environment => {
                let b = FIXED_BYTES + PER_INPUT_BYTE_IMAGE * self.input_bytes;
                (b, 2 * b)
            }
            _ => {
                let b = FIXED_BYTES + PER_INPUT_BYTE * self.input_bytes;
                (b, b)
            }
        }
    }
    fn over_budget(&self) -> bool {
        let (largest, peak) = self.bounds();
        self.usage.largest > largest || self.usage.peak > peak
    }
    fn usage_text(&self) -> String {
        let (largest, peak) = self.bounds();
        format!(
            "largest allocation {} bytes (bound {largest}), peak {} bytes (bound {peak})",
            self.usage.largest, self.usage.peak
        )
    }
}

fn written(f: &seeds::SeedFile, content: Vec<u8>) -> Vec<u8> {
    match f.post {
        Post::Gzip => seeds::gzip(&content),
        _ => content,
    }
}

fn donors(seeds: &[Seed]) -> Donors<'_> {
    let files: Vec<(&[u8], usize)> = seeds
        .iter()
        .flat_map(|s| &s.files)
        .filter(|f| f.weight > 0)
        .map(|f| (f.bytes.as_slice(), f.text_len))
        .collect();
    let mut words: Vec<Vec<u8>> = files
        .iter()
        .flat_map(|(b, t)| {
            let text = &b[..*t];
            mutate::words(text)
                .into_iter()
                .map(move |(a, e)| text[a..e].to_vec())
        })
        .filter(|w| w.len() <= 40)
        .collect();
    words.sort();
    words.dedup();
    Donors { files, words }
}

/// A seed as it is, with the options of a plain call.
fn unmutated(k: usize, s: &Seed) -> Case {
    Case {
        seed: k,
        files: s
            .files
            .iter()
            .map(|f| (f.name.clone(), written(f, f.bytes.clone())))
            .collect(),
        entry: s.entry,
        opts: LoadOptions {
            raw: s.raw,
            limits: Some(LIMITS),
            ..Default::default()
        },
    }
}

fn make_case(t: &Target, donors: &Donors, case_seed: u64) -> Case {
    let mut rng = Rng::new(case_seed);
    let k = rng.below(t.seeds.len());
    let s = &t.seeds[k];
    let mut case = unmutated(k, s);
    // The file to mutate, by weight.
    let total: u32 = s.files.iter().map(|f| f.weight).sum();
    let mut r = rng.below(total as usize) as u32;
    let i = s
        .files
        .iter()
        .position(|f| {
            let hit = r < f.weight;
            r = r.saturating_sub(f.weight);
            hit
        })
        .unwrap();
    let f = &s.files[i];
    let mut bytes = match (&f.dicom, f.post) {
        (Some(spec), _) if !rng.one_in(3) => {
            let b = spec.mutate(&mut rng);
            if rng.one_in(3) {
                mutate(&mut rng, &b, 0, &[], donors)
            } else {
                b
            }
        }
        (_, Post::Gzip) if rng.one_in(4) => {
            mutate(&mut rng, &seeds::gzip(&f.bytes), 0, &[], donors)
        }
        _ => written(f, mutate(&mut rng, &f.bytes, f.text_len, &f.fields, donors)),
    };
    if f.post == Post::Png && !rng.one_in(4) {
        mutate::fix_png_crcs(&mut bytes);
    }
    case.files[i].1 = bytes;
    if f.name_mutable && rng.one_in(3) {
        case.files[i].0 = mutate_name(&mut rng, &f.name, donors);
    }
    // A DICOM series with a slice missing or twice.
    if s.entry.is_none() && rng.one_in(10) {
        let j = rng.below(3);
        if rng.one_in(2) {
            case.files.remove(j);
        } else {
            let copy = (format!("copy{j}.dcm"), case.files[j].1.clone());
            case.files.push(copy);
        }
    }
    if t.kind == Kind::Volume {
        case.opts = volume_options(&mut rng, s);
    }
    case
}

fn volume_options(rng: &mut Rng, s: &Seed) -> LoadOptions {
    let limits = match rng.below(8) {
        0 | 1 => None,
        2 => Some(TINY),
        _ => Some(LIMITS),
    };
    let raw = s.raw.map(|mut l| {
        if rng.one_in(3) {
            l.dims[rng.below(3)] =
                *rng.pick(&[0, 1, 2, 4, 6, 2048, 2049, 65536, 1 << 20, u32::MAX]);
        }
        if rng.one_in(8) {
            l.kind = *rng.pick(&[
                ScalarKind::U8,
                ScalarKind::U16,
                ScalarKind::I16,
                ScalarKind::F32,
            ]);
        }
        if rng.one_in(8) {
            let v = *rng.pick(&[0.0, -1.0, f32::NAN, f32::INFINITY, 1e-30, 1e30, 0.5]);
            l.spacing = Some([1.0, v, 1.0]);
        }
        l
    });
    LoadOptions {
        raw,
        window: rng.one_in(10).then_some((-1000.0, 2000.0)),
        spacing: None,
        limits,
    }
}

/// Calls the parser and checks what it returned against its contract.
fn call(kind: Kind, path: &Path, opts: &LoadOptions) -> Verdict {
    match kind {
        Kind::Volume => match load_volume(path, opts) {
            Ok(v) => {
                if let Err(e) = v.validate() {
                    return Verdict::Violation(format!("accepted an invalid volume: {e:#}"));
                }
                if let Some(l) = opts.limits {
                    if let Err(e) = check_volume_limits(&v, l.max_3d_extent, l.bytes_available) {
                        return Verdict::Violation(format!(
                            "accepted a {:?} volume beyond the limits it was given ({l:?}): {e:#}",
                            v.dims
                        ));
                    }
                }
                Verdict::Accepted
            }
            Err(e) => {
                let msg = e.to_string();
                if msg.contains('\n') {
                    Verdict::Violation(format!("error on several lines: {msg:?}"))
                } else if !msg.starts_with(&path.display().to_string()) {
                    Verdict::Violation(format!("error does not start with the path: {msg:?}"))
                } else {
                    Verdict::Refused(msg)
                }
            }
        },
        Kind::Transfer => match TransferFunctions::load(path.to_str().unwrap()) {
            Ok(tf) => {
                let ok = tf
                    .colour
                    .points
                    .iter()
                    .all(|(s, v)| in01(*s) && v.iter().all(|x| x.is_finite() && *x >= 0.0))
                    && tf
                        .opacity
                        .points
                        .iter()
                        .all(|(s, v)| in01(*s) && in01(v[0]))
                    && tf
                        .medium
                        .points
                        .iter()
                        .all(|(s, v)| in01(*s) && v.iter().all(|x| in01(*x)))
                    && tf.eta.points.iter().all(|(s, v)| {
                        in01(*s) && (MIN_ETA as f32..=MAX_ETA as f32).contains(&v[0])
                    });
                if ok {
                    Verdict::Accepted
                } else {
                    Verdict::Violation(format!("accepted values out of range: {tf:?}"))
                }
            }
            Err(e) => Verdict::Refused(format!("{e:#}")),
        },
        Kind::Scene => match Scene::load(path) {
            Ok(_) => Verdict::Accepted,
            Err(e) => Verdict::Refused(format!("{e:#}")),
        },
        Kind::Environment => match EnvironmentMap::load(path) {
            Ok(m) => {
                let ok = m.width == 2 * m.height
                    && m.pixels.len() == m.width as usize * m.height as usize
                    && m.pixels
                        .iter()
                        .flatten()
                        .all(|c| c.is_finite() && *c >= 0.0);
                if ok {
                    Verdict::Accepted
                } else {
                    Verdict::Violation(format!(
                        "accepted a bad map: {}x{}, {} pixels",
                        m.width,
                        m.height,
                        m.pixels.len()
                    ))
                }
            }
            Err(e) => Verdict::Refused(format!("{e:#}")),
        },
    }
}

fn in01(x: f32) -> bool {
    (0.0..=1.0).contains(&x)
}

/// Writes the case's files into `root/s<seed>/` and calls the parser, measured.
fn execute(t: &Target, root: &Path, case: &Case, case_seed: u64) -> Outcome {
    let dir = root.join(format!("s{}", case.seed));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in &case.files {
        std::fs::write(dir.join(name), bytes)
            .unwrap_or_else(|e| panic!("writing {name:?} for case {case_seed:#x}: {e}"));
    }
    let path = match case.entry {
        Some(i) => dir.join(&case.files[i].0),
        None => dir.clone(),
    };
    CASE_SEED.store(case_seed, Relaxed);
    *CASE_NAME.lock().unwrap_or_else(PoisonError::into_inner) = t.name;
    IN_CASE.with(|c| c.set(true));
    PANIC.with(|p| p.borrow_mut().take());
    let (result, usage) =
        measured(|| panic::catch_unwind(AssertUnwindSafe(|| call(t.kind, &path, &case.opts))));
    IN_CASE.with(|c| c.set(false));
    let panicked = PANIC.with(|p| p.borrow_mut().take());
    let (verdict, caught) = match result {
        Ok(v) => (v, panicked),
        Err(payload) => (
            Verdict::Crash(
                panicked.unwrap_or_else(|| format!("panic '{}'", payload_text(&*payload))),
            ),
            None,
        ),
    };
    Outcome {
        verdict,
        caught,
        usage,
        input_bytes: case.files.iter().map(|(_, b)| b.len()).sum(),
        kind: t.kind,
    }
}

fn env_u64(name: &str) -> Option<u64> {
    let v = std::env::var(name).ok()?;
    let v = v.trim();
    let parsed = match v.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => v.parse(),
    };
    Some(parsed.unwrap_or_else(|_| panic!("{name}={v:?} is not a number")))
}

/// Cases per parser: [`DEFAULT_ITERS`] unless `REFRAKT_FUZZ_ITERS` says otherwise.
fn iterations() -> u64 {
    env_u64("REFRAKT_FUZZ_ITERS").unwrap_or(DEFAULT_ITERS)
}

/// `REFRAKT_FUZZ_REPLAY=<parser>:<case seed>`.
fn replay() -> Option<(String, u64)> {
    let v = std::env::var("REFRAKT_FUZZ_REPLAY").ok()?;
    let (name, seed) = v
        .split_once(':')
        .unwrap_or_else(|| panic!("REFRAKT_FUZZ_REPLAY={v:?}: expected <parser>:<case seed>"));
    let seed = seed.trim();
    let seed = match seed.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => seed.parse(),
    }
    .unwrap_or_else(|_| panic!("REFRAKT_FUZZ_REPLAY={v:?}: bad case seed"));
    Some((name.to_string(), seed))
}

/// What a case was given, for the report: option and files (with their start, escaped).
fn describe(t: &Target, case: &Case) -> String {
    let mut s = format!(
        "seed file '{}', options {:?}\n",
        t.seeds[case.seed].label, case.opts
    );
    for (name, bytes) in &case.files {
        let head: String = bytes[..bytes.len().min(300)].escape_ascii().to_string();
        s += &format!("    {name:?} ({} bytes): b\"{head}\"\n", bytes.len());
    }
    s
}

fn verdict_text(o: &Outcome) -> String {
    match &o.verdict {
        Verdict::Accepted => "accepted".into(),
        Verdict::Refused(e) => format!("refused: {e}"),
        Verdict::Violation(e) => format!("CONTRACT VIOLATION: {e}"),
        Verdict::Crash(e) => format!("CRASH: {e}"),
    }
}

fn keep(dir: &Path, case: &Case) -> PathBuf {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    for (name, bytes) in &case.files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    dir.to_path_buf()
}

#[derive(Default)]
struct Stats {
    runs: u64,
    ok: u64,
    err: u64,
    crashes: u64,
    violations: u64,
    over_budget: u64,
    /// Refused from the header because of the device limits.
    refused_by_limits: u64,
    /// Panics inside a dependency that the parser caught and returned as an error.
    caught: u64,
    /// The first case of each distinct panic caught (at most 5).
    caught_kinds: Vec<(u64, String)>,
    largest: usize,
    /// The case that made the largest allocation.
    largest_case: u64,
    peak: usize,
}

fn run(mut t: Target) {
    let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
    record_panics_in_cases();
    if let Ok(only) = std::env::var("REFRAKT_FUZZ_SEEDS") {
        t.seeds.retain(|s| s.label.contains(&only));
        if t.seeds.is_empty() {
            return;
        }
    }
    let donors = donors(&t.seeds);
    let root = tempfile::tempdir().unwrap();
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));

    if let Some((name, seed)) = replay() {
        if name == t.name {
            let case = make_case(&t, &donors, seed);
            // Kept first: the case may abort the process.
            let kept = keep(&tmp.join("fuzz-replay").join(t.name), &case);
            eprintln!(
                "fuzz {} case {seed:#x}: input in {}",
                t.name,
                kept.display()
            );
            let o = execute(&t, root.path(), &case, seed);
            eprintln!(
                "fuzz {} case {seed:#x}: {}\n  {}\n  {}",
                t.name,
                verdict_text(&o),
                o.usage_text(),
                describe(&t, &case),
            );
        }
        return;
    }

    // Every seed must load as it is: else the seed or the parser is broken, and the
    // counts below would mean nothing.
    for (k, s) in t.seeds.iter().enumerate() {
        let case = unmutated(k, s);
        let o = execute(&t, root.path(), &case, 0);
        assert!(
            matches!(o.verdict, Verdict::Accepted) && !o.over_budget(),
            "{}: seed '{}' must load: {} ({})",
            t.name,
            s.label,
            verdict_text(&o),
            o.usage_text()
        );
    }

    let start = Instant::now();
    let base = env_u64("REFRAKT_FUZZ_SEED").unwrap_or(0) ^ hash(t.name);
    let mut st = Stats::default();
    let mut reports = Vec::new();
    for i in 0..iterations() {
        let seed = case_seed(base, i);
        let case = make_case(&t, &donors, seed);
        let o = execute(&t, root.path(), &case, seed);
        st.runs += 1;
        if o.usage.largest > st.largest {
            (st.largest, st.largest_case) = (o.usage.largest, seed);
        }
        st.peak = st.peak.max(o.usage.peak);
        let failed = match &o.verdict {
            Verdict::Accepted => {
                st.ok += 1;
                false
            }
            Verdict::Refused(e) => {
                st.err += 1;
                if e.contains("(from the header") {
                    st.refused_by_limits += 1;
                }
                false
            }
            Verdict::Violation(_) => {
                st.violations += 1;
                true
            }
            Verdict::Crash(_) => {
                st.crashes += 1;
                true
            }
        };
        if o.over_budget() {
            st.over_budget += 1;
        }
        if let Some(p) = &o.caught {
            st.caught += 1;
            if st.caught_kinds.len() < 5 && st.caught_kinds.iter().all(|(_, q)| q != p) {
                st.caught_kinds.push((seed, p.clone()));
            }
        }
        if (failed || o.over_budget()) && reports.len() < 5 {
            let kept = keep(
                &tmp.join("fuzz-failures")
                    .join(format!("{}-{seed:016x}", t.name)),
                &case,
            );
            reports.push(format!(
                "{} case {seed:#x}: {}\n  {}\n  {}  input kept in {}\n  replay: \
                 REFRAKT_FUZZ_REPLAY={}:{seed:#x} cargo test --release --test fuzz -- \
                 --nocapture\n",
                t.name,
                verdict_text(&o),
                o.usage_text(),
                describe(&t, &case),
                kept.display(),
                t.name
            ));
        }
    }
    let limits = match t.kind {
        Kind::Volume => format!(
            "; refused from the header by the limits {}",
            st.refused_by_limits
        ),
        _ => String::new(),
    };
    eprintln!(
        "fuzz {:<11} {:>6} executions ({} seeds): ok {:>5}, err {:>5}, crashes {}, contract \
         violations {}, over the memory bound {}{limits}; largest allocation {} KiB (case \
         {:#x}), peak {} KiB; {:.2} s",
        t.name,
        st.runs,
        t.seeds.len(),
        st.ok,
        st.err,
        st.crashes,
        st.violations,
        st.over_budget,
        st.largest.div_ceil(1024),
        st.largest_case,
        st.peak.div_ceil(1024),
        start.elapsed().as_secs_f64()
    );
    if st.caught > 0 {
        // Not a failure of the parser (it returned an error), but a bug in a dependency.
        eprintln!(
            "fuzz {}: {} panics inside dependencies were caught by the parser and returned as \
             errors:",
            t.name, st.caught
        );
        for (seed, p) in &st.caught_kinds {
            eprintln!("  first in case {seed:#x}: {p}");
        }
    }
    for r in &reports {
        eprintln!("{r}");
    }
    assert!(
        st.crashes == 0 && st.violations == 0 && st.over_budget == 0,
        "fuzz {}: {} crashes, {} contract violations, {} calls over the memory bound:\n{}",
        t.name,
        st.crashes,
        st.violations,
        st.over_budget,
        reports.join("\n")
    );
    if st.runs >= 50 {
        assert!(
            st.err > 0,
            "fuzz {}: no mutated input was refused; is the mutator broken?",
            t.name
        );
        assert!(
            st.ok > 0,
            "fuzz {}: no mutated input was accepted; is the parser or the mutator broken?",
            t.name
        );
    }
}

// ---------------------------------------------------------------------------------------
// The parsers

#[test]
fn fuzz_raw() {
    run(Target {
        name: "raw",
        kind: Kind::Volume,
        seeds: seeds::raw(),
    });
}

#[test]
fn fuzz_nrrd() {
    run(Target {
        name: "nrrd",
        kind: Kind::Volume,
        seeds: seeds::nrrd_seeds(),
    });
}

#[test]
fn fuzz_nifti() {
    run(Target {
        name: "nifti",
        kind: Kind::Volume,
        seeds: seeds::nifti(),
    });
}

#[test]
fn fuzz_metaimage() {
    run(Target {
        name: "metaimage",
        kind: Kind::Volume,
        seeds: seeds::metaimage(),
    });
}

#[test]
fn fuzz_vti() {
    run(Target {
        name: "vti",
        kind: Kind::Volume,
        seeds: seeds::vti_seeds(),
    });
}

#[test]
fn fuzz_dicom() {
    run(Target {
        name: "dicom",
        kind: Kind::Volume,
        seeds: seeds::dicom_seeds(),
    });
}

#[test]
fn fuzz_transfer() {
    run(Target {
        name: "transfer",
        kind: Kind::Transfer,
        seeds: seeds::transfer(),
    });
}

#[test]
fn fuzz_scene() {
    run(Target {
        name: "scene",
        kind: Kind::Scene,
        seeds: seeds::scene(),
    });
}

#[test]
fn fuzz_environment() {
    run(Target {
        name: "environment",
        kind: Kind::Environment,
        seeds: seeds::environment(),
    });
}

// ---------------------------------------------------------------------------------------
// Headers that claim huge volumes, case by case

/// `s` with the first `from` in any of its files replaced by `to`.
fn with_text(s: &Seed, from: &str, to: &str) -> Option<Seed> {
    let mut s = s.clone();
    for f in &mut s.files {
        if let Some(i) = f
            .bytes
            .windows(from.len())
            .position(|w| w == from.as_bytes())
        {
            f.bytes.splice(i..i + from.len(), to.bytes());
            s.label = format!("{} with '{to}'", s.label);
            return Some(s);
        }
    }
    None
}

/// Every volume seed with dimensions beyond the device's extent, beyond its memory, and
/// at the edge of the header's integer type.
fn huge_variants() -> Vec<(&'static str, Vec<Seed>)> {
    const HUGE: [[u64; 3]; 3] = [
        [2049, 4, 3],
        [2000, 2000, 2000],
        [4294967295, 4294967295, 4294967295],
    ];
    let text = |seeds: Vec<Seed>, from: &str, to: &dyn Fn([u64; 3]) -> String| -> Vec<Seed> {
        seeds
            .iter()
            .flat_map(|s| HUGE.iter().filter_map(|&d| with_text(s, from, &to(d))))
            .collect()
    };
    let mut raw = Vec::new();
    for s in seeds::raw() {
        for d in HUGE {
            let mut v = s.clone();
            if let Some(l) = &mut v.raw {
                l.dims = d.map(|x| x as u32);
            } else {
                let f = &mut v.files[0];
                f.name = f
                    .name
                    .replace("5x4x3", &format!("{}x{}x{}", d[0], d[1], d[2]));
            }
            v.label = format!("{} as {d:?}", s.label);
            raw.push(v);
        }
    }
    let mut nifti = Vec::new();
    for s in seeds::nifti() {
        for d in [[2049, 4, 3], [2000, 2000, 2000], [32767, 32767, 32767]] {
            let mut v = s.clone();
            let f = &mut v.files[0];
            let be = f.fields[0].be;
            for (i, x) in d.iter().enumerate() {
                let b = if be {
                    (*x as i16).to_be_bytes()
                } else {
                    (*x as i16).to_le_bytes()
                };
                f.bytes[42 + 2 * i..44 + 2 * i].copy_from_slice(&b);
            }
            v.label = format!("{} as {d:?}", s.label);
            nifti.push(v);
        }
    }
    let mut dicom = Vec::new();
    for s in seeds::dicom_seeds() {
        for side in [2049u16, 65535] {
            let mut v = s.clone();
            for f in &mut v.files {
                if let Some(spec) = &mut f.dicom {
                    for e in &mut spec.elems {
                        if matches!(e.tag, (0x0028, 0x0010) | (0x0028, 0x0011)) {
                            e.value = dicom::Value::Us(side);
                        }
                    }
                    f.bytes = spec.to_bytes();
                }
            }
            v.label = format!("{} at {side}x{side} pixels", s.label);
            dicom.push(v);
        }
    }
    vec![
        ("raw", raw),
        (
            "nrrd",
            text(seeds::nrrd_seeds(), "sizes: 5 4 3", &|d| {
                format!("sizes: {} {} {}", d[0], d[1], d[2])
            }),
        ),
        ("nifti", nifti),
        (
            "metaimage",
            text(seeds::metaimage(), "DimSize = 5 4 3", &|d| {
                format!("DimSize = {} {} {}", d[0], d[1], d[2])
            }),
        ),
        (
            "vti",
            text(seeds::vti_seeds(), "WholeExtent=\"0 4 10 13 -1 1\"", &|d| {
                format!(
                    "WholeExtent=\"0 {} 0 {} 0 {}\"",
                    d[0] - 1,
                    d[1] - 1,
                    d[2] - 1
                )
            }),
        ),
        ("dicom", dicom),
    ]
}

/// A header claiming a huge volume is refused from the header when the device limits are
/// given, and against the bytes really present when they are not; either way nothing of
/// the claimed size is allocated (a few hundred KiB at most, for tiny files).
#[test]
fn huge_headers_are_refused_before_allocation() {
    let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
    record_panics_in_cases();
    let root = tempfile::tempdir().unwrap();
    let mut count = 0;
    for (name, variants) in huge_variants() {
        assert!(
            variants.len() >= 6,
            "{name}: only {} variants",
            variants.len()
        );
        let t = Target {
            name,
            kind: Kind::Volume,
            seeds: variants,
        };
        for (k, s) in t.seeds.iter().enumerate() {
            for limits in [Some(LIMITS), None] {
                let mut case = unmutated(k, s);
                case.opts.limits = limits;
                let o = execute(&t, root.path(), &case, 0);
                let what = format!(
                    "{name} '{}' with limits {limits:?}: {}; {}",
                    s.label,
                    verdict_text(&o),
                    o.usage_text()
                );
                let Verdict::Refused(msg) = &o.verdict else {
                    panic!("{what}")
                };
                // Refused from the header: beyond the limits, or a size that overflows.
                // (DICOM checks each file's pixel data against its header first.)
                if limits.is_some() && name != "dicom" {
                    assert!(
                        msg.contains("(from the header") || msg.contains("overflows"),
                        "{what}"
                    );
                }
                let small = (256 << 10) + 2 * o.input_bytes;
                assert!(
                    o.usage.largest <= small && o.usage.peak <= 2 * small,
                    "{what}"
                );
                count += 1;
            }
        }
    }
    // And every seed, as it is, on a device too small for it (4 voxels a side).
    for (name, seeds) in [
        ("raw", seeds::raw()),
        ("nrrd", seeds::nrrd_seeds()),
        ("nifti", seeds::nifti()),
        ("metaimage", seeds::metaimage()),
        ("vti", seeds::vti_seeds()),
        ("dicom", seeds::dicom_seeds()),
    ] {
        let t = Target {
            name,
            kind: Kind::Volume,
            seeds,
        };
        for (k, s) in t.seeds.iter().enumerate() {
            let mut case = unmutated(k, s);
            case.opts.limits = Some(TINY);
            let o = execute(&t, root.path(), &case, 0);
            let what = format!("{name} '{}' on {TINY:?}: {}", s.label, verdict_text(&o));
            assert!(
                matches!(&o.verdict, Verdict::Refused(m) if m.contains("(from the header")),
                "{what}"
            );
            count += 1;
        }
    }
    eprintln!(
        "{count} volumes beyond the device refused, none allocating more than 256 KiB + \
         twice the file"
    );
}

/// The harness itself: the counters see an allocation, and a case is a function of its
/// seed.
#[test]
fn the_harness_counts_and_replays() {
    let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
    let (v, u) = measured(|| vec![1u8; 10 << 20]);
    // (The counters are global: the test harness's own threads add a little noise.)
    assert!(u.largest >= 10 << 20 && u.peak >= 9 << 20, "{u:?}");
    drop(v);
    let (_, u) = measured(|| (0..1000).map(|i| i * 2).sum::<u64>());
    assert!(u.largest < 1 << 20 && u.peak < 1 << 20, "{u:?}");
    for (t, seeds) in [
        ("nrrd", seeds::nrrd_seeds()),
        ("dicom", seeds::dicom_seeds()),
    ] {
        let t = Target {
            name: t,
            kind: Kind::Volume,
            seeds,
        };
        let d = donors(&t.seeds);
        let mut changed = 0;
        for i in 0..50 {
            let a = make_case(&t, &d, case_seed(7, i));
            let b = make_case(&t, &d, case_seed(7, i));
            assert_eq!(a.files, b.files, "{} case {i} is not deterministic", t.name);
            assert_eq!(a.opts, b.opts);
            changed += (a.files != unmutated(a.seed, &t.seeds[a.seed]).files) as u32;
        }
        assert!(
            changed >= 45,
            "{}: only {changed} of 50 cases differ from their seed",
            t.name
        );
    }
}

/// Environment maps whose headers claim 32768×16384 pixels (8 GiB as f32 RGBA) in a file
/// of a few hundred bytes: refused before the pixel buffer is allocated.
#[test]
fn huge_environment_maps_are_refused_before_allocation() {
    let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
    record_panics_in_cases();
    let root = tempfile::tempdir().unwrap();
    let mut variants = Vec::new();
    for s in seeds::environment() {
        let mut v = s.clone();
        let f = &mut v.files[0];
        if f.name.ends_with(".exr") {
            let key = b"dataWindow\0box2i\0";
            let i = f.bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
            f.bytes[i + 8..i + 12].copy_from_slice(&32767i32.to_le_bytes());
            f.bytes[i + 12..i + 16].copy_from_slice(&16383i32.to_le_bytes());
        } else if f.name.ends_with(".png") {
            f.bytes[16..20].copy_from_slice(&32768u32.to_be_bytes());
            f.bytes[20..24].copy_from_slice(&16384u32.to_be_bytes());
            mutate::fix_png_crcs(&mut f.bytes);
        } else if f.name.ends_with(".hdr") {
            v = with_text(&s, "-Y 8 +X 16", "-Y 16384 +X 32768").unwrap();
        } else {
            continue;
        }
        variants.push(v);
    }
    assert_eq!(variants.len(), 7);
    let t = Target {
        name: "environment",
        kind: Kind::Environment,
        seeds: variants,
    };
    for (k, s) in t.seeds.iter().enumerate() {
        let o = execute(&t, root.path(), &unmutated(k, s), 0);
        let what = format!("'{}': {}; {}", s.label, verdict_text(&o), o.usage_text());
        assert!(matches!(o.verdict, Verdict::Refused(_)), "{what}");
        assert!(o.usage.peak <= 1 << 20, "{what}");
        eprintln!("{what}");
    }
}

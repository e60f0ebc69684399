//! Issue 33, items 3 and 4: caches verify themselves, and `precompute ambient`, whose job
//! is to write a table, fails when it cannot and never replaces a file that is not a
//! table unless asked (`--force`).
//!
//! * The ambient table (src/render/ambient/table/) carries a CRC-32 in its header: a
//!   corrupt cached table is reported in one line and rebuilt (equal to a clean build);
//!   one given by path (`--ambient-table FILE`) is an error and is left alone.
//! * A cached stand-in (src/volume/standins/) stays a plain `.raw` with a `.check` file
//!   beside it: a raw file that does not match it (bytes set to 255, zeroed, flipped,
//!   truncated), a missing check file or one of another generator is reported in one line
//!   and regenerated; the image equals a clean run's byte for byte.
//! * `precompute ambient` checks its target before the build: with the default table
//!   (about 80 s to build on 2 cores) every refusal must come within seconds.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use common::*;
use refrakt::render::ambient::table::{self, AmbientTable, Source, TableParams};

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

// ---------------------------------------------------------------------------------------
// Ambient tables.

/// The flags of a table that builds in a fraction of a second.
const SMALL: [&str; 10] = [
    "--theta-bins",
    "3",
    "--extinction-bins",
    "3",
    "--g-bins",
    "3",
    "--paths",
    "64",
    "--threads",
    "2",
];

/// [`SMALL`]'s parameters.
fn small_params() -> TableParams {
    TableParams {
        theta_bins: 3,
        s_bins: 3,
        g_bins: 3,
        paths: 64,
        ..TableParams::default()
    }
}

fn precompute(extra: &[&str]) -> Output {
    let mut args = vec!["precompute", "ambient"];
    args.extend_from_slice(&SMALL);
    args.extend_from_slice(extra);
    refrakt(&args)
}

/// The ways a cache file gets damaged: the damaged bytes and what the report must say.
fn damages(clean: &[u8]) -> Vec<(&'static str, Vec<u8>)> {
    let n = clean.len();
    let mut flipped = clean.to_vec();
    for i in [n / 2, n / 2 + 1, n - 5] {
        flipped[i] ^= 0x5a;
    }
    let mut quarter = clean.to_vec();
    let q = n / 4;
    quarter[n - q..].fill(255);
    vec![
        ("bytes flipped", flipped),
        ("a quarter set to 255", quarter),
        ("zeroed", vec![0; n]),
        ("truncated", clean[..n - n / 3].to_vec()),
    ]
}

/// A table whose values in one eighth of the scattered array are 50.0, the rest intact
/// (the case: rendered linear values off by up to 43, silently).
fn fifty_in_an_eighth(clean: &[u8], p: &TableParams) -> Vec<u8> {
    let mut b = clean.to_vec();
    let n = p.entries();
    let arrays = 4 * (2 * n + 2 * (p.s_bins * p.g_bins) as usize);
    let start = b.len() - arrays; // the first array, scattered
    for j in 0..n / 8 {
        let at = start + 4 * j;
        b[at..at + 4].copy_from_slice(&50.0f32.to_le_bytes());
    }
    b
}

/// The cached table of `precompute ambient` (no --out), damaged in each way: the next
/// run says so in one line naming the file, rebuilds it, and the rebuilt table's values
/// equal a clean build's.
#[test]
fn a_damaged_cached_table_is_reported_once_and_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().to_str().unwrap();
    let o = precompute(&["--cache-dir", cache]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let file = dir.path().join(small_params().file_name());
    let clean_bytes = std::fs::read(&file).unwrap();
    let clean = AmbientTable::load(&file).unwrap();
    let mut cases = damages(&clean_bytes);
    cases.push((
        "50.0 in an eighth",
        fifty_in_an_eighth(&clean_bytes, &clean.params),
    ));
    for (what, bytes) in cases {
        std::fs::write(&file, &bytes).unwrap();
        let o = precompute(&["--cache-dir", cache]);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{what}: {out}\n{err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.contains("ambient-a")).collect();
        assert_eq!(lines.len(), 1, "{what}: not one line: {err}");
        assert!(lines[0].contains("replacing it"), "{what}: {err}");
        assert!(out.contains("built in"), "{what}: not rebuilt: {out}");
        let rebuilt = AmbientTable::load(&file).unwrap();
        assert_eq!(rebuilt.scattered, clean.scattered, "{what}");
        assert_eq!(rebuilt.transmission, clean.transmission, "{what}");
        assert_eq!(rebuilt.scattered_err, clean.scattered_err, "{what}");
    }
    // The reasons, from the loader.
    let reason = |bytes: &[u8]| {
        std::fs::write(&file, bytes).unwrap();
        format!("{:#}", AmbientTable::load(&file).unwrap_err())
    };
    let e = reason(&fifty_in_an_eighth(&clean_bytes, &clean.params));
    assert!(e.contains(&*file.to_string_lossy()), "{e}");
    assert!(
        e.contains("corrupt: the payload does not match its checksum"),
        "{e}"
    );
    let e = reason(&damages(&clean_bytes)[3].1);
    assert!(e.contains("truncated"), "{e}");
}

/// The render path's implicit cache (`table::load_or_build`, what `--model ambient`
/// without `--ambient-table` uses): a damaged table is rebuilt, equal to a clean one.
#[test]
fn the_renderers_cache_rebuilds_a_damaged_table() {
    let dir = tempfile::tempdir().unwrap();
    let p = TableParams {
        seed: 5,
        ..small_params()
    };
    let none = |_: u64, _: u64| {};
    let (clean, src) = table::load_or_build(&p, Some(dir.path()), 2, &none).unwrap();
    let file = dir.path().join(p.file_name());
    assert!(matches!(src, Source::Built { written: Some(ref f), .. } if *f == file));
    let clean_bytes = std::fs::read(&file).unwrap();
    let mut cases = damages(&clean_bytes);
    cases.push(("50.0 in an eighth", fifty_in_an_eighth(&clean_bytes, &p)));
    for (what, bytes) in cases {
        std::fs::write(&file, &bytes).unwrap();
        let (t, src) = table::load_or_build(&p, Some(dir.path()), 2, &none).unwrap();
        assert!(matches!(src, Source::Built { .. }), "{what}: {src:?}");
        assert_eq!(t.scattered, clean.scattered, "{what}");
        assert_eq!(t.transmission, clean.transmission, "{what}");
        let (_, src) = table::load_or_build(&p, Some(dir.path()), 2, &none).unwrap();
        assert_eq!(src, Source::Cached(file.clone()), "{what}: not rewritten");
    }
}

/// A 24² render of the ambient model with `table`.
fn render_ambient(table: &Path, out: &Path) -> Output {
    refrakt(&[
        "render",
        "--model",
        "ambient",
        "--volume-size",
        "16",
        "--width",
        "24",
        "--height",
        "24",
        "--ambient-table",
        table.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
}

/// `--ambient-table FILE` that fails the check is an error naming the file and the
/// reason; the file is left as it was and nothing is rendered. The intact table renders.
#[test]
fn a_damaged_table_given_by_path_is_an_error_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mine.bin");
    let o = precompute(&["--out", file.to_str().unwrap()]);
    assert!(o.status.success(), "{:?}", text(&o));
    let clean = std::fs::read(&file).unwrap();
    let png = dir.path().join("a.png");
    let o = render_ambient(&file, &png);
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(png.exists());
    std::fs::remove_file(&png).unwrap();
    let p = small_params();
    let mut cases = damages(&clean);
    cases.push(("50.0 in an eighth", fifty_in_an_eighth(&clean, &p)));
    for (what, bytes) in cases {
        std::fs::write(&file, &bytes).unwrap();
        let o = render_ambient(&file, &png);
        let (out, err) = text(&o);
        assert!(!o.status.success(), "{what}: exit 0\n{out}\n{err}");
        assert!(!err.contains("panicked"), "{what}: {err}");
        assert!(
            err.contains("mine.bin"),
            "{what}: the file is not named: {err}"
        );
        assert!(
            err.contains("checksum") || err.contains("truncated") || err.contains("magic"),
            "{what}: no reason: {err}"
        );
        assert_eq!(
            std::fs::read(&file).unwrap(),
            bytes,
            "{what}: the file changed"
        );
        assert!(!png.exists(), "{what}: an image was written");
    }
}

/// Runs `precompute ambient` with the default (large) table and `extra`, asserting that
/// it refuses within seconds (before the build, about 80 s on 2 cores) with an error that
/// names `names`.
fn refused_before_the_build(extra: &[&str], names: &str, what: &str) -> String {
    let mut args = vec!["precompute", "ambient", "--threads", "2"];
    args.extend_from_slice(extra);
    let t = Instant::now();
    let o = refrakt(&args);
    let took = t.elapsed();
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{what}: exit 0\n{out}\n{err}");
    assert_ne!(o.status.code(), None, "{what}: killed by a signal: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert!(err.contains(names), "{what}: {names} not named: {err}");
    assert!(
        took < Duration::from_secs(10),
        "{what}: took {took:?}: not refused before the build"
    );
    assert!(!out.contains("built in"), "{what}: {out}");
    err
}

/// Targets that cannot be written are refused before the build (the issue: each of these
/// once warned after the build and exited 0).
#[test]
fn precompute_refuses_a_target_it_cannot_write_before_building() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    std::fs::create_dir(d("folder")).unwrap();
    std::fs::write(d("file"), b"a file").unwrap();

    let e = refused_before_the_build(&["--out", &s(&d("folder"))], "folder", "--out a folder");
    assert!(e.contains("is a folder"), "{e}");
    let e = refused_before_the_build(
        &["--out", &s(&d("file/t.bin"))],
        "file/t.bin",
        "--out in a file",
    );
    assert!(e.contains("is a file"), "{e}");
    let e = refused_before_the_build(
        &["--cache-dir", &s(&d("file"))],
        "file",
        "--cache-dir a file",
    );
    assert!(e.contains("is a file"), "{e}");
    let dangling = d("dangling.bin");
    std::os::unix::fs::symlink(d("nowhere/x.bin"), &dangling).unwrap();
    refused_before_the_build(&["--out", &s(&dangling)], "dangling.bin", "a dangling link");
    assert_eq!(std::fs::read(d("file")).unwrap(), b"a file");

    // A read-only folder, as --out's folder and as --cache-dir. Root writes there anyway
    // (permission bits do not stop it): then there is nothing to refuse.
    use std::os::unix::fs::PermissionsExt as _;
    let ro = d("readonly");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(ro.join("probe"), b"").is_ok() {
        eprintln!(
            "skipped: the read-only folder cases (this user, probably root, can write into a \
             0555 folder); the folder-is-a-file cases above cover the refusal"
        );
    } else {
        let out = ro.join("t.bin");
        let e = refused_before_the_build(&["--out", &s(&out)], "t.bin", "--out read-only");
        assert!(e.contains("cannot write"), "{e}");
        let e = refused_before_the_build(&["--cache-dir", &s(&ro)], "readonly", "read-only cache");
        assert!(e.contains("cannot write"), "{e}");
        assert!(!out.exists());
    }
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// An existing `--out` that is not an ambient table (a text file, a link to it, a table
/// zeroed so it lost its header) is refused before the build, byte for byte intact;
/// `--force` replaces it (through the link: the link stays). A table of other parameters
/// is ours: replaced, in one line.
#[test]
fn precompute_replaces_only_its_own_files_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let precious = dir.path().join("precious.txt");
    let content = b"my notes, not a table\n".to_vec();
    std::fs::write(&precious, &content).unwrap();
    let link = dir.path().join("link.bin");
    std::os::unix::fs::symlink(&precious, &link).unwrap();
    for target in [&precious, &link] {
        let t = target.to_str().unwrap();
        let e = refused_before_the_build(&["--out", t], t, "a file that is not a table");
        assert!(e.contains("not an ambient table"), "{e}");
        assert!(e.contains("--force"), "{e}");
        assert_eq!(std::fs::read(&precious).unwrap(), content, "{t} changed");
    }
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());

    // Forced, through the link: the file it points to gets the table.
    let o = precompute(&["--out", link.to_str().unwrap(), "--force"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(err.contains("replacing it"), "{err}");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let t = AmbientTable::load(&precious).unwrap();
    assert_eq!(t.params, small_params());

    // A table of other parameters is replaced without --force, saying so.
    let o = precompute(&["--out", precious.to_str().unwrap(), "--seed", "9"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(err.contains("other parameters (seed 1, wanted 9)"), "{err}");
    assert_eq!(AmbientTable::load(&precious).unwrap().params.seed, 9);

    // Zeroed, the file is no longer recognisably a table: refused, then forced.
    let n = std::fs::metadata(&precious).unwrap().len() as usize;
    std::fs::write(&precious, vec![0u8; n]).unwrap();
    let p = precious.to_str().unwrap();
    refused_before_the_build(&["--out", p], p, "a zeroed table");
    assert_eq!(std::fs::read(&precious).unwrap(), vec![0u8; n]);
    let o = precompute(&["--out", p, "--force"]);
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(AmbientTable::load(&precious).is_ok());
}

/// A write that fails after the build fails the command (a link to /dev/full, --force:
/// a device is never a table).
#[test]
fn precompute_fails_when_the_write_fails() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("full.bin");
    std::os::unix::fs::symlink("/dev/full", &link).unwrap();
    let l = link.to_str().unwrap();
    refused_before_the_build(&["--out", l], "full.bin", "/dev/full without --force");
    let o = precompute(&["--out", l, "--force"]);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "exit 0\n{out}\n{err}");
    assert!(err.contains("full.bin"), "{err}");
    assert!(err.contains("No space left"), "{err}");
    assert!(!out.contains("written:"), "{out}");
}

// ---------------------------------------------------------------------------------------
// Stand-ins.

/// `render hand` at a tiny scale with the cache in `cache`, into `png`.
fn render_hand(cache: &Path, png: &Path) -> Output {
    refrakt_command(&[
        "render",
        "--scene",
        "hand",
        "--scale",
        "0.05",
        "--model",
        "ea",
        "--no-preintegration",
        "--width",
        "16",
        "--height",
        "16",
        "-o",
        png.to_str().unwrap(),
    ])
    .env("REFRAKT_CACHE_DIR", cache)
    .output()
    .expect("running refrakt")
}

fn only(dir: &Path, suffix: &str) -> PathBuf {
    let found: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(suffix))
        .collect();
    assert_eq!(found.len(), 1, "{suffix} in {}: {found:?}", dir.display());
    found[0].clone()
}

/// `refrakt generate hand --scale 0.05` with the cache in `cache` (no GPU work).
fn generate_hand(cache: &Path) -> Output {
    refrakt_command(&["generate", "hand", "--scale", "0.05"])
        .env("REFRAKT_CACHE_DIR", cache)
        .output()
        .expect("running refrakt")
}

/// Checks the one line that reports a damaged stand-in cache.
fn reported_once(o: &Output, raw_name: &str, reason: &str, what: &str) {
    let (out, err) = text(o);
    assert!(o.status.success(), "{what}: {out}\n{err}");
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("stand-in cache"))
        .collect();
    assert_eq!(lines.len(), 1, "{what}: not one line: {err}");
    assert!(lines[0].contains(raw_name), "{what}: {err}");
    assert!(lines[0].contains(reason), "{what}: no '{reason}': {err}");
    assert!(lines[0].contains("regenerating"), "{what}: {err}");
}

/// A damaged stand-in cache (the issue: a quarter of the bytes set to 255, or all zeros,
/// rendered another image with exit 0) is reported in one line and regenerated; the image
/// equals a clean run's byte for byte and both files are rewritten clean. A missing check
/// file or one of another generator version (checked with `generate`, no render) too.
#[test]
fn a_damaged_standin_is_reported_once_and_regenerated() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let png = dir.path().join("hand.png");
    let o = render_hand(&cache, &png);
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(!text(&o).1.contains("stand-in cache"), "{:?}", text(&o));
    let clean_png = std::fs::read(&png).unwrap();
    let standins = cache.join("standins");
    let raw = only(&standins, ".raw");
    let check = only(&standins, ".raw.check");
    let (clean_raw, clean_check) = (std::fs::read(&raw).unwrap(), std::fs::read(&check).unwrap());
    let raw_name = raw.file_name().unwrap().to_string_lossy().into_owned();
    let rewritten = |what: &str| {
        assert!(
            std::fs::read(&raw).unwrap() == clean_raw,
            "{what}: raw not rewritten"
        );
        assert_eq!(std::fs::read(&check).unwrap(), clean_check, "{what}");
    };

    // The two cases through a render (about 8 s each on lavapipe, most of it the
    // one-off builds); flipped bytes and a truncated file through `generate` (no GPU):
    // the same cache files, so the same image.
    for (what, bytes) in damages(&clean_raw) {
        std::fs::write(&raw, &bytes).unwrap();
        let reason = if what == "truncated" {
            "truncated"
        } else {
            "do not match their checksum"
        };
        if what == "a quarter set to 255" || what == "zeroed" {
            std::fs::remove_file(&png).unwrap();
            reported_once(&render_hand(&cache, &png), &raw_name, reason, what);
            assert!(
                std::fs::read(&png).unwrap() == clean_png,
                "{what}: another image"
            );
        } else {
            reported_once(&generate_hand(&cache), &raw_name, reason, what);
        }
        rewritten(what);
    }

    std::fs::remove_file(&check).unwrap();
    reported_once(
        &generate_hand(&cache),
        &raw_name,
        "no check file",
        "no check",
    );
    rewritten("no check file");
    let other = String::from_utf8(clean_check.clone())
        .unwrap()
        .replace("\ngenerator ", "\ngenerator 9");
    std::fs::write(&check, other).unwrap();
    reported_once(
        &generate_hand(&cache),
        &raw_name,
        "generator version",
        "another generator",
    );
    rewritten("another generator");
    // The clean cache is used, silently.
    let o = generate_hand(&cache);
    assert!(!text(&o).1.contains("stand-in cache"), "{:?}", text(&o));
    assert!(text(&o).0.contains("read from cache"), "{:?}", text(&o));
}

/// `REFRAKT_CACHE_DIR=""` counts as unset: the stand-in goes to `$XDG_CACHE_HOME/refrakt`,
/// not to the working folder (the issue: it cached stand-ins in the working folder).
#[test]
fn an_empty_cache_variable_is_unset() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    let xdg = dir.path().join("xdg");
    std::fs::create_dir(&work).unwrap();
    let o = refrakt_command(&["generate", "hand", "--scale", "0.05"])
        .current_dir(&work)
        .env("REFRAKT_CACHE_DIR", "")
        .env("XDG_CACHE_HOME", &xdg)
        .output()
        .unwrap();
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(
        !work.join("standins").exists(),
        "cached in the working folder"
    );
    only(&xdg.join("refrakt/standins"), ".raw");
}

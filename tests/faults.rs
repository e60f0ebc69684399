//! Issue 33, item 1: outputs are written atomically. A write that fails (a full device, a
//! full file system) fails the command with the file and the reason, leaves what was at
//! the path byte for byte, and leaves no partial or temporary file.
//!
//! The full file system is a tmpfs of a few KiB mounted by the test; where that is not
//! allowed (not root, no mount in the container) that part is skipped with the reason on
//! stderr. `/dev/full` needs nothing and always runs.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::*;

/// A small, fast render (the EA ray marcher, 24²) into `output`.
fn render_into(output: &Path) -> Output {
    refrakt(&[
        "render",
        "--model",
        "ea",
        "--width",
        "24",
        "--height",
        "24",
        "-o",
        output.to_str().unwrap(),
    ])
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_failed_naming(o: &Output, file: &Path, what: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{what}: exit 0; stderr: {err}");
    assert!(!err.contains("panicked"), "{what}: panicked: {err}");
    let name = file.file_name().unwrap().to_string_lossy();
    assert!(
        err.contains(&*name),
        "{what}: the error does not name {name}: {err}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(!out.contains("wrote"), "{what}: says it wrote: {out}");
}

/// An image written through a link to /dev/full: the write's ENOSPC fails the command,
/// for both formats (the PNG path once said "wrote" and exited 0 here).
#[test]
fn an_image_written_to_a_full_device_fails() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["png", "exr"] {
        let link = dir.path().join(format!("full.{ext}"));
        std::os::unix::fs::symlink("/dev/full", &link).unwrap();
        let o = render_into(&link);
        assert_failed_naming(&o, &link, ext);
        assert!(
            stderr(&o).contains("No space left"),
            "{ext}: the reason is not given: {}",
            stderr(&o)
        );
    }
}

/// A tmpfs of 32 KiB mounted on a fresh folder, unmounted on drop.
struct TinyFs {
    dir: tempfile::TempDir,
}

impl TinyFs {
    fn mount() -> Result<Self, String> {
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        let o = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", "size=32k", "tmpfs"])
            .arg(dir.path())
            .output()
            .map_err(|e| format!("cannot run mount: {e}"))?;
        if !o.status.success() {
            return Err(format!(
                "mount -t tmpfs failed: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            ));
        }
        Ok(Self { dir })
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Fills the file system to the last byte with a filler file.
    fn fill(&self) {
        use std::io::Write as _;
        let mut f = std::fs::File::create(self.path().join("filler")).unwrap();
        let chunk = [0x5au8; 512];
        while f.write_all(&chunk).and_then(|_| f.flush()).is_ok() {}
        // What is left is less than a chunk: single bytes.
        while f.write_all(&[0x5a]).and_then(|_| f.flush()).is_ok() {}
    }

    fn entries(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(self.path())
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TinyFs {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount")
            .arg(self.dir.path())
            .output();
    }
}

/// On a file system with no space left, a render over an existing image fails naming
/// the file, the image survives byte for byte, and no temporary file is left beside it.
#[test]
fn a_failed_write_leaves_the_previous_image() {
    let fs = match TinyFs::mount() {
        Ok(fs) => fs,
        Err(why) => {
            eprintln!("skipped: no tiny file system to fill ({why})");
            return;
        }
    };
    let previous = |ext: &str| format!("the previous {ext} image, kept").into_bytes();
    let target = |ext: &str| fs.path().join(format!("previous.{ext}"));
    for ext in ["png", "exr"] {
        std::fs::write(target(ext), previous(ext)).unwrap();
    }
    fs.fill();
    let before = fs.entries();
    for ext in ["png", "exr"] {
        let o = render_into(&target(ext));
        assert_failed_naming(&o, &target(ext), ext);
        assert_eq!(
            std::fs::read(target(ext)).unwrap(),
            previous(ext),
            "{ext}: the previous file changed"
        );
        assert_eq!(fs.entries(), before, "{ext}: files were left behind");
    }
}

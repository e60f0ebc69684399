//! Writing the files the program makes (images, dumps, reports, charts, caches) so that a
//! failure never leaves a partial file and never destroys what was there before (issue 33).
//!
//! [`write_atomically`] writes the whole content to a temporary file in the target's
//! folder, flushes and syncs it, then renames it over the target: the target is either
//! its old content or the new one, whatever fails (a full disk, a signal, a crash). Every
//! error names the file and the reason. Callers encode into memory first (PNG, EXR, JSON,
//! SVG are all small next to a frame's GPU work), so an encoder's write error cannot be
//! swallowed by a buffered writer: the PNG path once reported "wrote" for a file on a
//! full disk and left 0 bytes (`image::save_buffer` into a full file system).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context as _, Result};

/// Writes `bytes` to `path` atomically (module docs). A link is followed: the file it
/// points to is replaced, the link stays. A target that exists and is not a regular file
/// (a character device such as /dev/null or /dev/full, a FIFO) cannot be replaced by a
/// rename: it is written in place, and its write errors still fail.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let target = resolve(path)?;
    let what = || describe(path, &target);
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => bail!("{}: is a folder; give a file name", what()),
        Ok(m) if !m.is_file() => {
            // A device or FIFO: no rename over it.
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&target)
                .with_context(|| format!("{}: cannot open for writing", what()))?;
            f.write_all(bytes)
                .and_then(|_| f.flush())
                .with_context(|| format!("{}: cannot write", what()))?;
            return Ok(());
        }
        _ => {}
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let existing = std::fs::metadata(&target).ok();
    let mut tmp = tempfile::Builder::new()
        .prefix(".refrakt-")
        .suffix(".partial")
        .tempfile_in(&dir)
        .with_context(|| {
            format!(
                "{}: cannot create a temporary file in {}",
                what(),
                dir.display()
            )
        })?;
    tmp.write_all(bytes)
        .and_then(|_| tmp.flush())
        .and_then(|_| tmp.as_file().sync_all())
        .with_context(|| format!("{}: cannot write", what()))?;
    // The new file gets the old one's permissions, or rw-r--r-- (a temporary file is made
    // owner-only).
    let permissions = match &existing {
        Some(m) => m.permissions(),
        None => {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::Permissions::from_mode(0o644)
        }
    };
    tmp.as_file()
        .set_permissions(permissions)
        .with_context(|| format!("{}: cannot set the permissions", what()))?;
    tmp.persist(&target)
        .map_err(|e| anyhow!("{}: cannot replace the file: {}", what(), e.error))?;
    // The rename itself durable too; a folder that cannot be synced is not an error.
    if let Ok(d) = std::fs::File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Checks, before any work, that `path` can be written by [`write_atomically`]: its
/// folder exists and is a folder, it is not itself a folder, and a file can be created in
/// that folder (tried, not guessed from permission bits: root ignores them, a read-only
/// mount does not). A device or FIFO already at the path is written in place: no folder
/// check. The error names the file and the reason.
pub fn check_writable(path: &Path) -> Result<()> {
    let target = resolve(path)?;
    let what = || describe(path, &target);
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => bail!("{}: is a folder; give a file name", what()),
        Ok(m) if !m.is_file() => return Ok(()),
        _ => {}
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => bail!("{}: {} is a file, not a folder", what(), dir.display()),
        Err(_) => bail!("{}: the folder {} does not exist", what(), dir.display()),
    }
    tempfile::Builder::new()
        .prefix(".refrakt-")
        .suffix(".probe")
        .tempfile_in(&dir)
        .map(drop)
        .map_err(|e| {
            anyhow!(
                "{}: cannot write in the folder {}: {}",
                what(),
                dir.display(),
                reason(&e)
            )
        })
}

/// Checks every output of a command before any work ([`check_writable`]), and that none
/// of them is one of its `inputs` or another of its outputs: the same file after links
/// are resolved (device and inode compared), so `render --env a.png -o a.png` cannot
/// replace the map it reads. `outputs` pairs each path with the option that named it.
pub fn check_outputs(outputs: &[(&str, &Path)], inputs: &[PathBuf]) -> Result<()> {
    for (flag, path) in outputs {
        check_writable(path).with_context(|| flag.to_string())?;
        let Some(id) = file_id(path) else { continue };
        if let Some(input) = inputs.iter().find(|p| file_id(p) == Some(id)) {
            bail!(
                "{flag} {}: is the input {}; the output would replace it (choose another \
                 file name)",
                path.display(),
                input.display()
            );
        }
    }
    // Outputs that do not exist yet have no inode: their (resolved) names are compared too.
    for (i, (flag, path)) in outputs.iter().enumerate() {
        let id = file_id(path);
        if let Some((other, _)) = outputs[..i]
            .iter()
            .find(|(_, p)| (id.is_some() && file_id(p) == id) || same_name(p, path))
        {
            bail!(
                "{flag} {}: is also the output of {other}; give each output its own file",
                path.display()
            );
        }
    }
    Ok(())
}

/// Device and inode of the file at `path` (links followed), if it exists.
fn file_id(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt as _;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// Whether two paths name the same file that may not exist yet: their folders
/// canonicalized, their file names compared.
fn same_name(a: &Path, b: &Path) -> bool {
    let key = |p: &Path| {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        let dir = std::fs::canonicalize(dir.unwrap_or(Path::new("."))).ok()?;
        Some(dir.join(p.file_name()?))
    };
    match (key(a), key(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// An I/O error's reason without the "(os error N)" tail.
fn reason(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// `path`, and where it leads when it is a link.
fn describe(path: &Path, target: &Path) -> String {
    if target == path {
        path.display().to_string()
    } else {
        format!("{} (-> {})", path.display(), target.display())
    }
}

/// The path a write to `path` lands on: links followed (every component), or `path`
/// itself when it does not exist yet. A link whose target is missing is an error (a
/// rename would replace the link).
pub(crate) fn resolve(path: &Path) -> Result<PathBuf> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path).map_err(|e| {
            anyhow!(
                "{}: is a link to a file that cannot be reached ({e})",
                path.display()
            )
        }),
        _ => Ok(path.to_path_buf()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_write_replaces_the_content_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomically(&p, b"first").unwrap();
        write_atomically(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "only the file itself is left");
        use std::os::unix::fs::PermissionsExt as _;
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o644);
    }

    #[test]
    fn a_link_is_followed_and_kept() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.txt");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomically(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
    }

    #[test]
    fn a_full_device_is_an_error() {
        let e = write_atomically(Path::new("/dev/full"), &[0u8; 4096]).unwrap_err();
        assert!(format!("{e:#}").contains("/dev/full"), "{e:#}");
    }
}

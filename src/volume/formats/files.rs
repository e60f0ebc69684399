//! Reading volume files safely: only regular files (a FIFO or device could block or never
//! end), never more bytes than a header promises, and one-line reasons when a path cannot
//! be read.

use std::io::Read;
use std::path::Path;

use anyhow::{anyhow, ensure, Result};

/// Why `path` cannot be read as a file, in a few words, or `None` when it is a regular
/// file: "no such file", "is a directory", "a FIFO", or the system's reason (e.g. "Too
/// many levels of symbolic links" for a symlink loop, "Permission denied").
pub fn why_not_a_file(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => None,
        Ok(m) if m.is_dir() => Some("is a directory, not a file".into()),
        Ok(m) => Some(format!("is not a regular file ({})", file_kind(&m))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            // A dangling symlink reads as "not found" too; say so.
            if std::fs::symlink_metadata(path).is_ok() {
                Some("is a symbolic link to nothing".into())
            } else {
                Some("no such file".into())
            }
        }
        Err(e) => Some(e.to_string()),
    }
}

/// What a path that is not a regular file or directory is, for messages.
pub(crate) fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "not a regular file"
    }
}

/// Reads a whole regular file, naming it in the error (a FIFO or device is refused: it
/// could block or never end).
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    read_file_at_most(path, None)
}

/// A file that should hold at most `promised` bytes (a header's skip plus its data):
/// refused from its size if longer, so a lying header or a huge file costs nothing; read
/// whole otherwise (shorter files are the caller's to report as truncated).
pub(crate) fn read_promised(path: &Path, what: &str, promised: u64) -> Result<Vec<u8>> {
    let len = regular_file(path)?.metadata().map_or(0, |m| m.len());
    ensure!(
        len <= promised,
        "{what} is {len} bytes, the header promises {promised} bytes (file too long)"
    );
    read_file_at_most(path, Some(promised))
}

/// `path` opened, if it is a regular file (a FIFO or device could block or never end).
fn regular_file(path: &Path) -> Result<std::fs::File> {
    let err = |e: std::io::Error| anyhow!("cannot read '{}': {e}", path.display());
    let file = std::fs::File::open(path).map_err(err)?;
    let meta = file.metadata().map_err(err)?;
    ensure!(
        meta.is_file(),
        "'{}' is not a regular file ({})",
        path.display(),
        file_kind(&meta)
    );
    Ok(file)
}

/// [`read_file`], reading at most `limit` bytes when given (what a header promises).
pub(crate) fn read_file_at_most(path: &Path, limit: Option<u64>) -> Result<Vec<u8>> {
    let err = |e: std::io::Error| anyhow!("cannot read '{}': {e}", path.display());
    let file = regular_file(path)?;
    let size = file.metadata().map_err(err)?.len();
    let len = limit.map_or(size, |l| l.min(size));
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(len).read_to_end(&mut bytes).map_err(err)?;
    Ok(bytes)
}

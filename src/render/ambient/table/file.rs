//! The table's file: its format (a header with the parameters and a CRC-32, then the
//! arrays), atomic saves, checked loads, and the cache folder where tables are kept.

use super::*;

/// Version of the file format and of the estimator; part of the cache file's name.
/// Version 2: the header ends with a CRC-32 of the rest of the file (issue 33).
pub const FORMAT_VERSION: u32 = 2;
/// The first bytes of every table file: what marks a file as ours.
pub const MAGIC: [u8; 8] = *b"RFKAMBT\0";
/// Bytes before the arrays: magic, version, the parameters, the build's seconds and the
/// checksum.
const HEADER_BYTES: usize = 8 + 4 + 4 + 4 * 3 + 4 + 4 + 8 + 8 + 4;
/// Where the checksum sits: the header's last four bytes.
const CRC_AT: usize = HEADER_BYTES - 4;

/// CRC-32 (IEEE) of a file's bytes without its checksum field: the header before it and
/// every array after it.
fn checksum(bytes: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..CRC_AT]);
    h.update(&bytes[HEADER_BYTES..]);
    h.finalize()
}

impl AmbientTable {
    /// Write the table to `path` atomically (a temporary file beside it, then a rename),
    /// making its folder if needed.
    pub fn save(&self, path: &Path) -> Result<()> {
        let p = &self.params;
        let mut bytes = Vec::with_capacity(
            HEADER_BYTES + 4 * (self.scattered.len() * 2 + self.transmission.len() * 2),
        );
        bytes.extend_from_slice(&MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&p.albedo.to_le_bytes());
        for n in [p.theta_bins, p.s_bins, p.g_bins] {
            bytes.extend_from_slice(&n.to_le_bytes());
        }
        bytes.extend_from_slice(&p.s_max.to_le_bytes());
        bytes.extend_from_slice(&p.paths.to_le_bytes());
        bytes.extend_from_slice(&p.seed.to_le_bytes());
        bytes.extend_from_slice(&self.build_seconds.to_le_bytes());
        bytes.extend_from_slice(&[0; 4]); // the checksum, filled in below
        debug_assert_eq!(bytes.len(), HEADER_BYTES);
        for a in [
            &self.scattered,
            &self.scattered_err,
            &self.transmission,
            &self.transmission_err,
        ] {
            for v in a.iter() {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        let crc = checksum(&bytes);
        bytes[CRC_AT..HEADER_BYTES].copy_from_slice(&crc.to_le_bytes());
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        }
        crate::files::write_atomically(path, &bytes)
            .with_context(|| format!("{}: cannot write the ambient table", path.display()))
    }

    /// Read a table written by [`AmbientTable::save`], checking the magic, version,
    /// parameters, size, the checksum (header and arrays) and that every value is finite;
    /// errors name the file and the reason.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path)
            .map_err(|e| anyhow!("{}: cannot read the ambient table: {e}", path.display()))?;
        Self::parse(&bytes)
            .with_context(|| format!("{}: not a usable ambient table", path.display()))
    }

    fn parse(bytes: &[u8]) -> Result<Self> {
        ensure!(
            bytes.len() >= HEADER_BYTES,
            "truncated: {} bytes, shorter than the {HEADER_BYTES}-byte header",
            bytes.len()
        );
        ensure!(
            bytes[..8] == MAGIC,
            "wrong magic (not an ambient table file)"
        );
        let mut at = 8;
        let mut take = |n: usize| {
            let b = &bytes[at..at + n];
            at += n;
            b
        };
        let u32_ = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("4 bytes"));
        let f32_ = |b: &[u8]| f32::from_le_bytes(b.try_into().expect("4 bytes"));
        let version = u32_(take(4));
        ensure!(
            version == FORMAT_VERSION,
            "format version {version}, this build reads version {FORMAT_VERSION}"
        );
        let albedo = f32_(take(4));
        let theta_bins = u32_(take(4));
        let s_bins = u32_(take(4));
        let g_bins = u32_(take(4));
        let s_max = f32_(take(4));
        let paths = u32_(take(4));
        let seed = u64::from_le_bytes(take(8).try_into().expect("8 bytes"));
        let build_seconds = f64::from_le_bytes(take(8).try_into().expect("8 bytes"));
        let stored_crc = u32_(take(4));
        let params = TableParams {
            albedo,
            theta_bins,
            s_bins,
            g_bins,
            s_max,
            paths,
            seed,
        };
        params
            .validate()
            .context("invalid parameters in the header")?;
        let n3 = params.entries();
        let n2 = s_bins as usize * g_bins as usize;
        let expected = HEADER_BYTES + 4 * (2 * n3 + 2 * n2);
        ensure!(
            bytes.len() == expected,
            "{} bytes where parameters {}x{}x{} need {expected} (truncated or padded)",
            bytes.len(),
            theta_bins,
            s_bins,
            g_bins
        );
        let crc = checksum(bytes);
        ensure!(
            crc == stored_crc,
            "corrupt: the payload does not match its checksum (CRC-32 {crc:08x}, the header \
             says {stored_crc:08x})"
        );
        let mut arrays = Vec::with_capacity(4);
        let mut off = HEADER_BYTES;
        for (name, n) in [
            ("scattered", n3),
            ("scattered error", n3),
            ("transmission", n2),
            ("transmission error", n2),
        ] {
            let a: Vec<f32> = bytes[off..off + 4 * n].chunks_exact(4).map(f32_).collect();
            off += 4 * n;
            if let Some(j) = a.iter().position(|v| !v.is_finite()) {
                bail!("{name} value {j} is {} (not finite)", a[j]);
            }
            arrays.push(a);
        }
        let transmission_err = arrays.pop().expect("four arrays");
        let transmission = arrays.pop().expect("four arrays");
        let scattered_err = arrays.pop().expect("four arrays");
        let scattered = arrays.pop().expect("four arrays");
        Ok(Self {
            params,
            scattered,
            scattered_err,
            transmission,
            transmission_err,
            build_seconds,
        })
    }
}

/// The cache folder: `dir` if given, else `$REFRAKT_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/refrakt`, else `$HOME/.cache/refrakt`.
pub fn cache_dir(dir: Option<&Path>) -> Result<PathBuf> {
    if let Some(d) = dir {
        return Ok(d.to_path_buf());
    }
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    if let Some(d) = var("REFRAKT_CACHE_DIR") {
        return Ok(PathBuf::from(d));
    }
    if let Some(d) = var("XDG_CACHE_HOME") {
        return Ok(PathBuf::from(d).join("refrakt"));
    }
    if let Some(h) = var("HOME") {
        return Ok(PathBuf::from(h).join(".cache").join("refrakt"));
    }
    bail!("no cache folder: pass one, or set REFRAKT_CACHE_DIR, XDG_CACHE_HOME or HOME")
}

/// The table of `params` from the cache (see [`cache_dir`]), else built and written there.
/// A corrupt (checksum), truncated or mismatched file is reported in one warning and
/// rebuilt. A table that cannot be written is a warning too, not an error: this is the
/// renderer's implicit cache, and rendering, not caching, is the caller's job (`refrakt
/// precompute ambient`, whose job is the file, checks with [`check_target`] and fails).
pub fn load_or_build(
    params: &TableParams,
    cache_dir: Option<&Path>,
    threads: usize,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(AmbientTable, Source)> {
    params.validate()?;
    let path = self::cache_dir(cache_dir)?.join(params.file_name());
    if path.exists() {
        match AmbientTable::load(&path) {
            Ok(t) if t.params == *params => return Ok((t, Source::Cached(path))),
            Ok(t) => log::warn!(
                "{}: made with other parameters ({}); rebuilding",
                path.display(),
                t.params.differences(params)
            ),
            Err(e) => log::warn!("{e:#}; rebuilding"),
        }
    }
    let table = AmbientTable::build(params, threads, progress)?;
    let written = match table.save(&path) {
        Ok(()) => Some(path),
        Err(e) => {
            log::warn!("{e:#}; the table is not cached");
            None
        }
    };
    let seconds = table.build_seconds;
    Ok((table, Source::Built { seconds, written }))
}

/// What [`check_target`] found at a table's path.
#[derive(Debug)]
pub enum Existing {
    /// No file: it will be made.
    Nothing,
    /// An intact table of the parameters asked for.
    Table(AmbientTable),
    /// An ambient table file (it starts with [`MAGIC`]) that is not usable for these
    /// parameters, and why: other parameters, another format version, a checksum
    /// mismatch, truncated (the reason, without the file's name). Ours to replace.
    Stale(String),
    /// A file that is not an ambient table (no [`MAGIC`]): someone else's.
    Foreign,
}

/// Checks, before a (long) build, that a table for `params` can be written to `path`
/// and says what is there now: an error if `path` is a folder, a link to nothing, or in
/// a folder that cannot be created or written to (a probe file is made and removed).
/// Links are followed (the table replaces the file a link points to).
pub fn check_target(params: &TableParams, path: &Path) -> Result<Existing> {
    let target = crate::files::resolve(path)?;
    let existing = match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => bail!("{}: is a folder; give a file name", path.display()),
        // A device or FIFO: never a table (not read: a FIFO would block).
        Ok(m) if !m.is_file() => Existing::Foreign,
        Ok(_) => {
            use std::io::Read as _;
            let mut head = Vec::with_capacity(MAGIC.len());
            std::fs::File::open(&target)
                .and_then(|f| f.take(MAGIC.len() as u64).read_to_end(&mut head))
                .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
            if head != MAGIC {
                Existing::Foreign
            } else {
                let bytes = std::fs::read(&target)
                    .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
                match AmbientTable::parse(&bytes) {
                    Ok(t) if t.params == *params => Existing::Table(t),
                    Ok(t) => Existing::Stale(format!(
                        "a table made with other parameters ({})",
                        t.params.differences(params)
                    )),
                    Err(e) => Existing::Stale(format!("{e:#}")),
                }
            }
        }
        Err(e)
            if matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            Existing::Nothing
        }
        Err(e) => bail!("{}: {e}", path.display()),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| {
        // A file where a folder should be: name it.
        match dir.ancestors().find(|a| a.is_file()) {
            Some(f) => anyhow!(
                "{}: cannot create the folder {}: {} is a file",
                path.display(),
                dir.display(),
                f.display()
            ),
            None => anyhow!(
                "{}: cannot create the folder {}: {e}",
                path.display(),
                dir.display()
            ),
        }
    })?;
    // The folder can be written (tried), as every output is checked.
    crate::files::check_writable(path)?;
    Ok(existing)
}

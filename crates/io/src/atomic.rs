//! Atomic file output: write to a temporary sibling, sync, rename.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why an output could not be written. Nothing is left at `path` in any case.
#[derive(Debug, Error)]
pub enum AtomicWriteError {
    /// The folder does not exist or cannot be written.
    #[error("cannot write into folder {dir}: {source}")]
    Folder {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Writing, syncing or renaming failed.
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl AtomicWriteError {
    /// The underlying I/O error.
    pub fn io_error(&self) -> &std::io::Error {
        match self {
            AtomicWriteError::Folder { source, .. } | AtomicWriteError::Write { source, .. } => {
                source
            }
        }
    }
}

/// Writes `path` atomically: `fill` writes the content into a buffered temporary file in the
/// same folder, which is synced and renamed over `path` only if `fill` succeeds. On any error
/// the temporary file is removed and `path` is untouched. Errors of `fill` are returned as is.
pub fn write_atomic<E>(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E>
where
    E: From<AtomicWriteError>,
{
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(".snowscape-")
        .suffix(".partial")
        .tempfile_in(&dir)
        .map_err(|source| AtomicWriteError::Folder {
            dir: dir.clone(),
            source,
        })?;
    let (file, tmp_path) = tmp.into_parts();
    let mut writer = BufWriter::new(file);
    fill(&mut writer)?;
    let werr = |source| AtomicWriteError::Write {
        path: path.to_path_buf(),
        source,
    };
    writer.flush().map_err(werr)?;
    let file = writer.into_inner().map_err(|e| werr(e.into_error()))?;
    // Temporary files are created private (0600); an output is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(werr)?;
    }
    file.sync_all().map_err(werr)?;
    tmp_path.persist(path).map_err(|e| werr(e.error))?;
    Ok(())
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), AtomicWriteError> {
    write_atomic(path, |w| {
        w.write_all(bytes)
            .map_err(|source| AtomicWriteError::Write {
                path: path.to_path_buf(),
                source,
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_file() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.bin");
        write_bytes_atomic(&p, b"hello").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"hello");
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644, "outputs are readable by others");
        }
    }

    #[test]
    fn failed_fill_leaves_nothing() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("b.bin");
        std::fs::write(&p, b"old").unwrap();
        let r: Result<(), AtomicWriteError> = write_atomic(&p, |w| {
            w.write_all(b"partial").unwrap();
            Err(AtomicWriteError::Write {
                path: p.clone(),
                source: std::io::Error::other("encoder failed"),
            })
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_folder_is_a_folder_error() {
        let r = write_bytes_atomic(Path::new("/nonexistent-snowscape/x.bin"), b"x");
        assert!(matches!(r, Err(AtomicWriteError::Folder { .. })));
    }
}

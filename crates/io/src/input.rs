//! Opening input files: the one gate every reader goes through.
//!
//! [`open_regular`] refuses anything that is not a regular file (a character device such as
//! `/dev/zero` reads without end, a FIFO blocks on open until a writer comes, a directory
//! cannot be read) by looking at the path's metadata *before* opening it, so no check can
//! block; it then confirms on the open handle that the file is still a regular one and returns
//! its length, which readers use to bound what they allocate (a header may promise more cells
//! than the file holds). [`read_regular`] reads a whole regular file of at most `max_bytes`.
//!
//! Raster readers (ESRI ASCII, GeoTIFF, PNG16, RAW16, NPY, OpenEXR), their sidecars, the mesh
//! readers (OBJ, PLY, glTF and its buffers) and the scenario and forcing files use them.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The largest sidecar or text input read whole (scenario, forcing, `.prj`, JSON): 256 MiB.
pub const MAX_TEXT_BYTES: u64 = 1 << 28;

/// Why an input file could not be opened or read.
#[derive(Debug, Error)]
pub enum InputError {
    /// The path exists but is not a regular file (device, FIFO, socket, directory).
    #[error("{path} is {kind}, not a regular file: refusing to read it")]
    NotRegular { path: PathBuf, kind: &'static str },
    /// The file is larger than the reader may read whole.
    #[error("{path} is {bytes} bytes, more than the {max} bytes this input may hold")]
    TooLarge { path: PathBuf, bytes: u64, max: u64 },
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl InputError {
    /// The path the error is about.
    pub fn path(&self) -> &Path {
        match self {
            InputError::NotRegular { path, .. }
            | InputError::TooLarge { path, .. }
            | InputError::Io { path, .. } => path,
        }
    }
}

/// What a file type is, in words, for [`InputError::NotRegular`] (and the checkpoint
/// reader's own refusal).
pub fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> InputError + '_ {
    move |source| InputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Fails unless `path` (symbolic links followed) is a regular file; returns its length.
/// Looks at metadata only: nothing is opened, so a FIFO cannot block.
pub fn check_regular(path: &Path) -> Result<u64, InputError> {
    let meta = std::fs::metadata(path).map_err(io_error(path))?;
    if !meta.is_file() {
        return Err(InputError::NotRegular {
            path: path.to_path_buf(),
            kind: kind_of(meta.file_type()),
        });
    }
    Ok(meta.len())
}

/// Opens a regular file for reading and returns it with its length in bytes. Devices, FIFOs,
/// sockets and directories are refused before any open (see the module docs).
pub fn open_regular(path: &Path) -> Result<(File, u64), InputError> {
    check_regular(path)?;
    let file = File::open(path).map_err(io_error(path))?;
    // The path could have been replaced between the check and the open.
    let meta = file.metadata().map_err(io_error(path))?;
    if !meta.is_file() {
        return Err(InputError::NotRegular {
            path: path.to_path_buf(),
            kind: kind_of(meta.file_type()),
        });
    }
    Ok((file, meta.len()))
}

/// Reads a whole regular file of at most `max_bytes` bytes.
pub fn read_regular(path: &Path, max_bytes: u64) -> Result<Vec<u8>, InputError> {
    let (file, len) = open_regular(path)?;
    if len > max_bytes {
        return Err(InputError::TooLarge {
            path: path.to_path_buf(),
            bytes: len,
            max: max_bytes,
        });
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // `take` bounds the read even if the file grows while it is read.
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io_error(path))?;
    if bytes.len() as u64 > max_bytes {
        return Err(InputError::TooLarge {
            path: path.to_path_buf(),
            bytes: bytes.len() as u64,
            max: max_bytes,
        });
    }
    Ok(bytes)
}

/// Fills `buf` from `r` as far as the data goes; returns how many bytes were read (less than
/// `buf.len()` only at the end of the data).
pub fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Reads a whole regular UTF-8 text file of at most [`MAX_TEXT_BYTES`] bytes.
pub fn read_regular_text(path: &Path) -> Result<String, InputError> {
    let bytes = read_regular(path, MAX_TEXT_BYTES)?;
    String::from_utf8(bytes).map_err(|e| InputError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
    })
}

/// A seek or read at an offset past the end of the file: what a corrupt offset in a TIFF or
/// EXR directory leads to. Carried inside an [`std::io::Error`] by [`BoundedReader`] so that
/// the decoder's error can be turned back into a typed [`crate::RasterError::PastEnd`] naming
/// the offset, instead of the operating system's "Invalid argument (os error 22)".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("offset {offset} is past the end of the {len}-byte file")]
pub struct PastEnd {
    /// The offset that was asked for (as the file gives it, or as a decoder computed it).
    pub offset: u64,
    /// The file's length in bytes.
    pub len: u64,
}

impl PastEnd {
    /// The [`PastEnd`] an I/O error carries, if it is one.
    pub fn of(e: &std::io::Error) -> Option<PastEnd> {
        e.get_ref()?.downcast_ref::<PastEnd>().copied()
    }
}

/// A buffered reader over a regular file of known length whose seeks cannot leave the file:
/// a seek past the end (or before the start) fails with an [`std::io::Error`] carrying
/// [`PastEnd`] (kind `InvalidData`), before the operating system sees the offset. The TIFF
/// and EXR readers hand it to their decoders.
pub struct BoundedReader<R> {
    inner: R,
    pos: u64,
    len: u64,
}

impl<R> BoundedReader<R> {
    /// Wraps `inner`, positioned at the start of a file of `len` bytes.
    pub fn new(inner: R, len: u64) -> Self {
        Self { inner, pos: 0, len }
    }

    /// The file's length in bytes.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the file is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The current position, bytes from the start.
    pub fn position(&self) -> u64 {
        self.pos
    }
}

impl<R: Read> Read for BoundedReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.pos = self.pos.saturating_add(n as u64);
        Ok(n)
    }
}

impl<R: std::io::Seek> std::io::Seek for BoundedReader<R> {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        use std::io::SeekFrom;
        let target: i128 = match to {
            SeekFrom::Start(p) => i128::from(p),
            SeekFrom::Current(d) => i128::from(self.pos) + i128::from(d),
            SeekFrom::End(d) => i128::from(self.len) + i128::from(d),
        };
        if target < 0 || target > i128::from(self.len) {
            let offset = u64::try_from(target.max(0)).unwrap_or(u64::MAX);
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                PastEnd {
                    offset,
                    len: self.len,
                },
            ));
        }
        let target = target as u64;
        self.inner.seek(SeekFrom::Start(target))?;
        self.pos = target;
        Ok(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_opens_with_its_length() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        std::fs::write(&p, b"12345").unwrap();
        assert_eq!(open_regular(&p).unwrap().1, 5);
        assert_eq!(read_regular(&p, 5).unwrap(), b"12345");
        assert_eq!(read_regular_text(&p).unwrap(), "12345");
        let e = read_regular(&p, 4).unwrap_err();
        assert!(matches!(
            e,
            InputError::TooLarge {
                bytes: 5,
                max: 4,
                ..
            }
        ));
    }

    #[test]
    fn a_bounded_reader_refuses_seeks_past_the_end_with_the_offset() {
        use std::io::{Cursor, Seek, SeekFrom};
        let mut r = BoundedReader::new(Cursor::new(vec![1u8, 2, 3, 4]), 4);
        assert_eq!(r.seek(SeekFrom::Start(4)).unwrap(), 4);
        assert_eq!(r.seek(SeekFrom::Current(-2)).unwrap(), 2);
        let mut b = [0u8; 2];
        r.read_exact(&mut b).unwrap();
        assert_eq!((b, r.position()), ([3, 4], 4));
        // 2^64 - 616: the OS would say "Invalid argument (os error 22)".
        let e = r.seek(SeekFrom::Start(u64::MAX - 615)).unwrap_err();
        let p = PastEnd::of(&e).unwrap();
        assert_eq!((p.offset, p.len), (u64::MAX - 615, 4));
        assert_eq!(
            e.to_string(),
            "offset 18446744073709551000 is past the end of the 4-byte file"
        );
        assert!(PastEnd::of(&r.seek(SeekFrom::Current(-5)).unwrap_err()).is_some());
        assert!(PastEnd::of(&r.seek(SeekFrom::End(1)).unwrap_err()).is_some());
        // A refused seek leaves the position where it was.
        assert_eq!(r.position(), 4);
    }

    #[test]
    fn devices_and_directories_are_refused() {
        let e = open_regular(Path::new("/dev/zero")).unwrap_err();
        assert!(
            e.to_string().contains("/dev/zero is a character device"),
            "{e}"
        );
        let d = tempfile::tempdir().unwrap();
        let e = open_regular(d.path()).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let e = open_regular(&d.path().join("missing")).unwrap_err();
        assert!(matches!(e, InputError::Io { .. }));
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("pipe.asc");
        let ok = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return; // no mkfifo on this system
        }
        let e = open_regular(&p).unwrap_err();
        assert!(e.to_string().contains("FIFO"), "{e}");
    }
}

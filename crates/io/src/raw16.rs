//! RAW16 heightmaps (`.raw`, `.r16`), read and write.
//!
//! The Unreal / Unity terrain convention: little-endian u16 codes, row-major, first row north,
//! no header, usually square. The size comes from `--raw-size WxH`, else the sidecar, else a
//! square inferred from the file length (an error names the byte count when it is not twice a
//! perfect square). The height scale and geometry follow [`crate::heightmap16`], exactly as
//! for PNG16; the writer emits the same `<file>.json` sidecar.

use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cells};
use crate::error::{RasterError, Result, io_err, write_err};
use crate::heightmap16::{
    Png16Scale, read_sidecar, resolve_geometry, resolve_scale, write_sidecar,
};
use crate::write_atomic;
use snowscape_terrain::Grid;
use std::io::{Read, Write};
use std::path::Path;

/// Columns and rows from the options, the sidecar, or a square of `bytes / 2` cells.
fn raw_size(
    path: &Path,
    bytes: u64,
    opts: &ReadOptions,
    side: Option<(usize, usize)>,
) -> Result<(usize, usize)> {
    if let Some(s) = opts.raw_size.or(side) {
        return Ok(s);
    }
    let not_square = || RasterError::RawSize {
        path: path.to_path_buf(),
        bytes,
        expected: "twice a perfect square (a square grid of u16); give --raw-size WxH".into(),
    };
    if !bytes.is_multiple_of(2) || bytes == 0 {
        return Err(not_square());
    }
    let n = bytes / 2;
    let side = n.isqrt();
    if side * side != n {
        return Err(not_square());
    }
    let side = usize::try_from(side).map_err(|_| not_square())?;
    Ok((side, side))
}

/// Reads a RAW16 heightmap.
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    let bytes = crate::input::check_regular(path)?;
    let sidecar = read_sidecar(path)?;
    let (w, h) = raw_size(
        path,
        bytes,
        opts,
        sidecar.as_ref().map(|s| (s.width, s.height)),
    )?;
    let n = check_cells(path, w as u64, h as u64, opts.max_cells)?;
    if bytes != 2 * n as u64 {
        return Err(RasterError::RawSize {
            path: path.to_path_buf(),
            bytes,
            expected: format!("{} (2 bytes x {w} x {h})", 2 * n as u64),
        });
    }
    let scale = resolve_scale(path, "RAW16", opts, sidecar.as_ref())?;
    let geometry = resolve_geometry(path, "RAW16", (w, h), opts, sidecar.as_ref())?;
    // Streamed 64 KiB at a time: the memory is the grid's, not the grid's and the file's.
    let (file, _) = crate::input::open_regular(path)?;
    let mut file = file.take(2 * n as u64);
    let mut block = vec![0u8; 1 << 16];
    let mut sink = CellSink::new(path, w, h, NodataRule::declared(None));
    let mut read = 0u64;
    loop {
        let got = crate::input::read_full(&mut file, &mut block).map_err(io_err(path))?;
        read += got as u64;
        for pair in block[..got].chunks_exact(2) {
            let code = u16::from_le_bytes([pair[0], pair[1]]);
            if Some(code) == scale.nodata {
                sink.push_nodata();
            } else {
                sink.push_f64(scale.height(code, u16::MAX))?;
            }
        }
        if got < block.len() {
            break;
        }
    }
    if sink.len() != n {
        return Err(RasterError::RawSize {
            path: path.to_path_buf(),
            bytes: read,
            expected: format!("{} (the file changed while being read)", 2 * n),
        });
    }
    sink.finish(geometry)
}

/// Writes `grid` as RAW16 plus its `<path>.json` sidecar, atomically; returns the scale.
pub(crate) fn write(path: &Path, grid: &Grid) -> Result<Png16Scale> {
    let scale = Png16Scale::for_grid(grid);
    let codes = scale.encode(grid);
    write_atomic(path, |w| {
        for c in &codes {
            w.write_all(&c.to_le_bytes()).map_err(write_err(path))?;
        }
        Ok::<(), RasterError>(())
    })?;
    write_sidecar(path, &scale, grid.geometry())?;
    Ok(scale)
}

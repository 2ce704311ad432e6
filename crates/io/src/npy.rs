//! NumPy arrays (`.npy`), read and write, with the `npyz` crate.
//!
//! Format: NumPy's NPY 1.0/2.0/3.0 (`numpy.lib.format`): the magic `\x93NUMPY`, a version, a
//! header length, a Python dict literal `{'descr': '<f4', 'fortran_order': False,
//! 'shape': (rows, cols), }`, then the raw array. Reading accepts 2-D arrays of f32, f64, i8,
//! i16, i32, u8, u16, u32 in either byte order; Fortran order is transposed. Before `npyz`
//! parses anything, the header length is checked against the file size and the shape product
//! against [`crate::ReadOptions::max_cells`], and the data length is checked against the
//! shape, so a corrupt header can neither overflow nor allocate beyond the file.
//! NPY has no georeferencing: `--cell-size` is required. Nodata: NaN (the NumPy convention;
//! see [`crate::cells`]); infinity is an error.
//!
//! Writing: little-endian f32, C order, shape `(rows, cols)`, nodata cells as NaN.

use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cell_size, check_cells};
use crate::error::{MAX_ECHO, RasterError, Result, clip, geometry_err, io_err, write_err};
use crate::input::{check_regular, open_regular};
use crate::write_atomic;
use npyz::{DType, NpyFile, NpyHeader, Order, TypeChar, WriterBuilder};
use snowscape_terrain::{Grid, GridGeometry};
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::Path;

fn npy_err(path: &Path, reason: impl std::fmt::Display) -> RasterError {
    RasterError::Npy {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Reads the header text after checking the magic and that its length fits in the file.
fn header_text(path: &Path, file_len: u64) -> Result<String> {
    let (mut f, _) = open_regular(path)?;
    let mut pre = [0u8; 12];
    f.read_exact(&mut pre).map_err(|_| {
        npy_err(
            path,
            format!("{file_len} bytes is too short for an NPY header"),
        )
    })?;
    if &pre[..6] != b"\x93NUMPY" {
        return Err(npy_err(path, "missing the \\x93NUMPY magic"));
    }
    let (len, start) = match pre[6] {
        1 => (u64::from(u16::from_le_bytes([pre[8], pre[9]])), 10u64),
        2 | 3 => (
            u64::from(u32::from_le_bytes([pre[8], pre[9], pre[10], pre[11]])),
            12,
        ),
        v => return Err(npy_err(path, format!("unsupported NPY version {v}"))),
    };
    if start + len > file_len {
        return Err(npy_err(
            path,
            format!("header of {len} bytes runs past the end of the {file_len}-byte file"),
        ));
    }
    let mut text = vec![0u8; len as usize];
    f.seek(std::io::SeekFrom::Start(start))
        .and_then(|_| f.read_exact(&mut text))
        .map_err(io_err(path))?;
    Ok(String::from_utf8_lossy(&text).into_owned())
}

/// The product of every unquoted integer in the header (the shape, and any sub-array shapes
/// of exotic dtypes), or `None` on overflow.
fn unquoted_int_product(text: &str) -> Option<u64> {
    let (mut product, mut current, mut quote): (u64, Option<u64>, Option<char>) = (1, None, None);
    for c in text.chars().chain(std::iter::once(' ')) {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '\'' | '"') => quote = Some(c),
            (None, d) if d.is_ascii_digit() => {
                let digit = u64::from(d.to_digit(10)?);
                current = Some(current.unwrap_or(0).checked_mul(10)?.checked_add(digit)?);
            }
            (None, _) => {
                if let Some(v) = current.take() {
                    product = product.checked_mul(v)?;
                }
            }
        }
    }
    Some(product)
}

/// A sample type the reader accepts.
trait Cell: npyz::Deserialize + Copy {
    fn push(self, sink: &mut CellSink) -> Result<()>;
}

macro_rules! int_cell {
    ($($t:ty),*) => {$(
        impl Cell for $t {
            fn push(self, sink: &mut CellSink) -> Result<()> {
                sink.push_f64(f64::from(self))
            }
        }
    )*};
}
int_cell!(i8, i16, i32, u8, u16, u32, f64);

impl Cell for f32 {
    fn push(self, sink: &mut CellSink) -> Result<()> {
        sink.push_f32(self)
    }
}

/// Streams the array into `sink` in row-major order.
fn read_cells<T: Cell>(
    path: &Path,
    npy: NpyFile<BufReader<File>>,
    (w, h): (usize, usize),
    sink: &mut CellSink,
) -> Result<()> {
    let order = npy.order();
    let data = npy.data::<T>().map_err(|e| npy_err(path, e))?;
    match order {
        Order::C => {
            for v in data {
                v.map_err(io_err(path))?.push(sink)?;
            }
        }
        Order::Fortran => {
            let cols: Vec<T> = data.collect::<std::io::Result<_>>().map_err(io_err(path))?;
            for r in 0..h {
                for c in 0..w {
                    let v = cols
                        .get(c * h + r)
                        .ok_or_else(|| npy_err(path, "short data"))?;
                    v.push(sink)?;
                }
            }
        }
    }
    Ok(())
}

/// Dispatches on the dtype.
fn read_typed(
    path: &Path,
    npy: NpyFile<BufReader<File>>,
    wh: (usize, usize),
    sink: &mut CellSink,
) -> Result<()> {
    let dtype = npy.dtype();
    let DType::Plain(ts) = &dtype else {
        return Err(npy_err(
            path,
            format!("dtype {} is not a plain number", dtype.descr()),
        ));
    };
    match (ts.type_char(), ts.size_field()) {
        (TypeChar::Float, 4) => read_cells::<f32>(path, npy, wh, sink),
        (TypeChar::Float, 8) => read_cells::<f64>(path, npy, wh, sink),
        (TypeChar::Int, 1) => read_cells::<i8>(path, npy, wh, sink),
        (TypeChar::Int, 2) => read_cells::<i16>(path, npy, wh, sink),
        (TypeChar::Int, 4) => read_cells::<i32>(path, npy, wh, sink),
        (TypeChar::Uint, 1) => read_cells::<u8>(path, npy, wh, sink),
        (TypeChar::Uint, 2) => read_cells::<u16>(path, npy, wh, sink),
        (TypeChar::Uint, 4) => read_cells::<u32>(path, npy, wh, sink),
        _ => Err(npy_err(
            path,
            format!("dtype {ts} is not one of f4, f8, i1, i2, i4, u1, u2, u4"),
        )),
    }
}

/// Parses the header with `npyz` (after the pre-checks) and checks shape and data length.
fn open(path: &Path, max_cells: usize) -> Result<(NpyFile<BufReader<File>>, usize, usize)> {
    let file_len = check_regular(path)?;
    let text = header_text(path, file_len)?;
    let product = unquoted_int_product(&text).ok_or_else(|| {
        npy_err(
            path,
            format!("shape in header {:?} overflows", clip(&text, MAX_ECHO)),
        )
    })?;
    if product > max_cells as u64 {
        return Err(npy_err(
            path,
            format!(
                "header {:?} describes {product} values, more than the {max_cells} allowed",
                clip(&text, MAX_ECHO)
            ),
        ));
    }
    let mut reader = BufReader::new(open_regular(path)?.0);
    let header = NpyHeader::from_reader(&mut reader)
        .map_err(|e| npy_err(path, clip(&e.to_string(), MAX_ECHO)))?;
    let &[h, w] = header.shape() else {
        return Err(npy_err(
            path,
            format!("shape {:?} is not 2-D (rows, cols)", header.shape()),
        ));
    };
    let n = check_cells(path, w, h, max_cells)?;
    let pos = reader.stream_position().map_err(io_err(path))?;
    let item = header.dtype().num_bytes().unwrap_or(0) as u64;
    let need = item.saturating_mul(n as u64);
    if file_len.saturating_sub(pos) < need {
        return Err(npy_err(
            path,
            format!(
                "shape ({h}, {w}) of {item}-byte values needs {need} data bytes, the file has {}",
                file_len.saturating_sub(pos)
            ),
        ));
    }
    Ok((NpyFile::with_header(header, reader), w as usize, h as usize))
}

/// Reads a 2-D NumPy array as a DEM (`--cell-size` required).
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    let (npy, w, h) = open(path, opts.max_cells)?;
    let cell = opts.cell_size.ok_or_else(|| RasterError::MissingOption {
        path: path.to_path_buf(),
        format: "NPY",
        option: "--cell-size",
        why: "NumPy arrays carry no georeferencing",
    })?;
    let cell = check_cell_size(path, cell, "--cell-size")?;
    let geometry = GridGeometry::square(w, h, cell)
        .map(|g| g.with_crs(opts.crs.clone()))
        .map_err(geometry_err(path))?;
    let mut sink = CellSink::new(path, w, h, NodataRule::nan());
    read_typed(path, npy, (w, h), &mut sink)?;
    sink.finish(geometry)
}

/// Writes `grid` as a little-endian f32 C-order array of shape (rows, cols), nodata as NaN.
pub(crate) fn write(path: &Path, grid: &Grid) -> Result<()> {
    let g = grid.geometry();
    write_atomic(path, |out| {
        let mut writer = npyz::WriteOptions::<f32>::new()
            .default_dtype()
            .shape(&[g.height() as u64, g.width() as u64])
            .writer(out)
            .begin_nd()
            .map_err(write_err(path))?;
        for (i, v) in grid.data().iter().enumerate() {
            let v = if grid.mask().is_valid(i) {
                *v
            } else {
                f32::NAN
            };
            writer.push(&v).map_err(write_err(path))?;
        }
        writer.finish().map_err(write_err(path))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_product_ignores_quoted_digits_and_catches_overflow() {
        let h = "{'descr': '<f4', 'fortran_order': False, 'shape': (344, 403), }";
        assert_eq!(unquoted_int_product(h), Some(344 * 403));
        let big = "{'descr': '<f8', 'shape': (99999999999, 99999999999, 99999999999), }";
        assert_eq!(unquoted_int_product(big), None);
    }
}

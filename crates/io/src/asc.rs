//! ESRI ASCII grid (`.asc`), read and write.
//!
//! Format (ESRI "ASCII raster format", as read by GDAL's AAIGrid driver): a header of
//! `key value` lines, keys case-insensitive: `ncols`, `nrows`, `xllcorner` or `xllcenter`,
//! `yllcorner` or `yllcenter`, `cellsize` (or `dx` and `dy` for non-square cells, a GDAL
//! extension) and optionally `NODATA_value`; then `ncols * nrows` numbers separated by any
//! whitespace (rows may wrap across lines arbitrarily), first row north. `xllcenter` gives the
//! centre of the south-west cell: the corner is half a cell further south-west.
//!
//! Reading streams line by line into a reused buffer (no per-value allocation) and checks, with
//! line numbers in every error: the cell count against [`ReadOptions::max_cells`] before
//! allocating, the cell size, every token, the value count (too few and too many), and the
//! nodata rule of [`crate::cells`] (NaN is an error unless `NODATA_value` is NaN).
//! The CRS comes from [`ReadOptions::crs`], else a `.prj` / `CRS.txt` sidecar.
//!
//! Writing emits `xllcorner`/`yllcorner`, `cellsize` (or `dx`/`dy`), `NODATA_value -9999` and
//! shortest round-trip decimal values; a WKT CRS is written to a `.prj` sidecar (an EPSG-only
//! CRS cannot be expressed as WKT without a CRS database and is not written).

use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cell_size, check_cells};
use crate::crs_sidecar::sidecar_crs;
use crate::error::{RasterError, Result, geometry_err, io_err, write_err};
use crate::input::open_regular;
use crate::write_atomic;
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry};
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

/// The nodata value written by [`write`].
pub const ASC_NODATA: f64 = -9999.0;

/// The most bytes a line may hold per value of a row: 48, twice the longest shortest
/// round-trip f64 (`-1.2345678901234567e-308`, 24 characters) and its separator.
pub const MAX_LINE_BYTES_PER_VALUE: usize = 48;

/// The most bytes of any line beyond [`MAX_LINE_BYTES_PER_VALUE`] x `ncols` (header lines,
/// and every line before `ncols` is known): 64 KiB.
pub const MAX_LINE_BYTES_BASE: usize = 1 << 16;

/// A line-by-line reader over a reused byte buffer that counts lines. A line longer than
/// `max` bytes is an error: a file without line breaks cannot make the buffer grow to its
/// size.
struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    line: usize,
    max: usize,
    ncols: usize,
}

impl<R: BufRead> Lines<R> {
    /// Sets the line limit for rows of `ncols` values (see [`MAX_LINE_BYTES_PER_VALUE`]).
    fn set_ncols(&mut self, ncols: usize) {
        self.ncols = ncols;
        self.max = ncols
            .saturating_mul(MAX_LINE_BYTES_PER_VALUE)
            .saturating_add(MAX_LINE_BYTES_BASE);
    }

    /// Loads the next line into `buf`; false at end of file.
    fn advance(&mut self, path: &Path) -> Result<bool> {
        self.buf.clear();
        loop {
            let avail = self.reader.fill_buf().map_err(io_err(path))?;
            if avail.is_empty() {
                break;
            }
            let (take, done) = match avail.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (avail.len(), false),
            };
            if self.buf.len() + take > self.max {
                return Err(RasterError::AscLineTooLong {
                    path: path.to_path_buf(),
                    line: self.line + 1,
                    max: self.max,
                    per_value: MAX_LINE_BYTES_PER_VALUE,
                    ncols: self.ncols,
                });
            }
            self.buf.extend_from_slice(&avail[..take]);
            self.reader.consume(take);
            if done {
                break;
            }
        }
        if self.buf.is_empty() {
            return Ok(false);
        }
        self.line += 1;
        if self.line == 1 && self.buf.starts_with(b"\xEF\xBB\xBF") {
            self.buf.drain(..3);
        }
        Ok(true)
    }

    fn tokens(&self) -> impl Iterator<Item = &[u8]> {
        self.buf
            .split(u8::is_ascii_whitespace)
            .filter(|t| !t.is_empty())
    }
}

fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

fn lossy(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(token);
    s.chars().take(40).collect()
}

/// The header values, as found.
#[derive(Debug, Default)]
struct Header {
    ncols: Option<usize>,
    nrows: Option<usize>,
    /// (value, whether it is a cell centre)
    x: Option<(f64, bool)>,
    y: Option<(f64, bool)>,
    cellsize: Option<(f64, usize)>,
    dx: Option<(f64, usize)>,
    dy: Option<(f64, usize)>,
    nodata: Option<f64>,
}

impl Header {
    fn set(&mut self, path: &Path, line: usize, key: &[u8], value: Option<&[u8]>) -> Result<()> {
        let key_s = lossy(key).to_ascii_lowercase();
        let bad = |reason: &'static str| RasterError::AscHeader {
            path: path.to_path_buf(),
            line,
            key: lossy(key),
            value: value.map(lossy).unwrap_or_default(),
            reason,
        };
        let raw = value.ok_or_else(|| bad("the key has no value"))?;
        let num = || parse_f64(raw).ok_or_else(|| bad("the value is not a number"));
        let count = || {
            std::str::from_utf8(raw)
                .ok()
                .and_then(|s| s.parse::<usize>().ok())
                .filter(|&n| n > 0)
                .ok_or_else(|| bad("the value is not a positive whole number"))
        };
        match key_s.as_str() {
            "ncols" => self.ncols = Some(count()?),
            "nrows" => self.nrows = Some(count()?),
            "xllcorner" => self.x = Some((num()?, false)),
            "xllcenter" => self.x = Some((num()?, true)),
            "yllcorner" => self.y = Some((num()?, false)),
            "yllcenter" => self.y = Some((num()?, true)),
            "cellsize" => self.cellsize = Some((num()?, line)),
            "dx" => self.dx = Some((num()?, line)),
            "dy" => self.dy = Some((num()?, line)),
            "nodata_value" => self.nodata = Some(num()?),
            _ => return Err(bad("unknown header key")),
        }
        Ok(())
    }
}

/// Reads header lines until the first line that starts with a number, which stays loaded.
fn read_header<R: BufRead>(path: &Path, lines: &mut Lines<R>) -> Result<(Header, bool)> {
    let mut header = Header::default();
    loop {
        if let Some(ncols) = header.ncols {
            // Known from an earlier line: it sizes the limit of the lines after it.
            lines.set_ncols(ncols);
        }
        if !lines.advance(path)? {
            break;
        }
        let mut tokens = lines.tokens();
        let Some(first) = tokens.next() else { continue };
        if parse_f64(first).is_some() {
            return Ok((header, true));
        }
        let value = tokens.next();
        header.set(path, lines.line, first, value)?;
    }
    Ok((header, false))
}

/// The validated size and georeferencing of a header.
struct Layout {
    ncols: usize,
    nrows: usize,
    transform: GeoTransform,
}

fn layout(path: &Path, h: &Header, header_end: usize) -> Result<Layout> {
    let missing = |key| RasterError::AscMissingKey {
        path: path.to_path_buf(),
        key,
        line: header_end,
    };
    let ncols = h.ncols.ok_or_else(|| missing("ncols"))?;
    let nrows = h.nrows.ok_or_else(|| missing("nrows"))?;
    let (x, x_centre) = h.x.ok_or_else(|| missing("xllcorner or xllcenter"))?;
    let (y, y_centre) = h.y.ok_or_else(|| missing("yllcorner or yllcenter"))?;
    let (pw, ph) = match (h.dx, h.dy, h.cellsize) {
        (Some(dx), Some(dy), _) => (dx, dy),
        (_, _, Some(c)) => (c, c),
        _ => return Err(missing("cellsize (or dx and dy)")),
    };
    let pw = check_cell_size(path, pw.0, &format!("the header (line {})", pw.1))?;
    let ph = check_cell_size(path, ph.0, &format!("the header (line {})", ph.1))?;
    let x0 = if x_centre { x - 0.5 * pw } else { x };
    let y0 = if y_centre { y - 0.5 * ph } else { y };
    Ok(Layout {
        ncols,
        nrows,
        transform: GeoTransform {
            origin_x: x0,
            origin_y: y0 + nrows as f64 * ph,
            pixel_width: pw,
            pixel_height: ph,
        },
    })
}

/// Counts the tokens left in the file (after a count overflow), for the error message.
fn count_rest<R: BufRead>(path: &Path, lines: &mut Lines<R>, mut found: usize) -> Result<usize> {
    while lines.advance(path)? {
        found += lines.tokens().count();
    }
    Ok(found)
}

/// Streams the data values into `sink`, starting with the line already loaded.
fn read_values<R: BufRead>(
    path: &Path,
    lines: &mut Lines<R>,
    sink: &mut CellSink,
    lay: &Layout,
) -> Result<()> {
    let expected = lay.ncols * lay.nrows;
    let count_err = |found, line| RasterError::AscValueCount {
        path: path.to_path_buf(),
        ncols: lay.ncols,
        nrows: lay.nrows,
        expected,
        found,
        line,
    };
    let mut last_line = lines.line;
    loop {
        let mut overflow = 0;
        for token in lines.tokens() {
            if sink.len() == expected {
                overflow += 1;
                continue;
            }
            let v = parse_f64(token).ok_or_else(|| RasterError::AscToken {
                path: path.to_path_buf(),
                line: lines.line,
                token: lossy(token),
            })?;
            if !(v as f32).is_finite() && !sink.is_nodata(v) {
                // Quoted as written: `1e999` parses to infinity, which says nothing.
                let i = sink.len();
                return Err(RasterError::AscValue {
                    path: path.to_path_buf(),
                    line: lines.line,
                    col: i % lay.ncols,
                    row: i / lay.ncols,
                    token: lossy(token),
                });
            }
            sink.push_f64(v)?;
            last_line = lines.line;
        }
        if overflow > 0 {
            let line = lines.line;
            let found = count_rest(path, lines, expected + overflow)?;
            return Err(count_err(found, line));
        }
        if !lines.advance(path)? {
            break;
        }
    }
    if sink.len() < expected {
        return Err(count_err(sink.len(), last_line));
    }
    Ok(())
}

/// Reads an ESRI ASCII grid.
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    let (file, file_len) = open_regular(path)?;
    let mut lines = Lines {
        reader: BufReader::with_capacity(1 << 16, file),
        buf: Vec::new(),
        line: 0,
        max: MAX_LINE_BYTES_BASE,
        ncols: 0,
    };
    let (header, has_data) = read_header(path, &mut lines)?;
    let lay = layout(path, &header, lines.line)?;
    check_cells(path, lay.ncols as u64, lay.nrows as u64, opts.max_cells)?;
    // Each value takes at least two bytes: a lying header cannot reserve more than the file.
    let room = usize::try_from(file_len / 2 + 1).unwrap_or(usize::MAX);
    let n = (lay.ncols * lay.nrows).min(room);
    let rule = NodataRule::declared(header.nodata);
    let mut sink = CellSink::with_capacity(path, lay.ncols, n, rule);
    if has_data {
        read_values(path, &mut lines, &mut sink, &lay)?;
    } else {
        return Err(RasterError::AscValueCount {
            path: path.to_path_buf(),
            ncols: lay.ncols,
            nrows: lay.nrows,
            expected: lay.ncols * lay.nrows,
            found: 0,
            line: lines.line,
        });
    }
    let crs = match &opts.crs {
        Some(c) => Some(c.clone()),
        None => sidecar_crs(path)?,
    };
    let geometry = GridGeometry::from_transform(lay.ncols, lay.nrows, lay.transform, crs)
        .map_err(geometry_err(path))?;
    sink.finish(geometry)
}

fn write_header(w: &mut impl Write, g: &GridGeometry) -> std::io::Result<()> {
    let t = g.transform();
    writeln!(w, "ncols {}", g.width())?;
    writeln!(w, "nrows {}", g.height())?;
    writeln!(w, "xllcorner {}", t.origin_x)?;
    writeln!(
        w,
        "yllcorner {}",
        t.origin_y - g.height() as f64 * t.pixel_height
    )?;
    if t.pixel_width == t.pixel_height {
        writeln!(w, "cellsize {}", t.pixel_width)?;
    } else {
        writeln!(w, "dx {}", t.pixel_width)?;
        writeln!(w, "dy {}", t.pixel_height)?;
    }
    writeln!(w, "NODATA_value {ASC_NODATA}")
}

fn write_body(w: &mut impl Write, grid: &Grid) -> std::io::Result<()> {
    write_header(w, grid.geometry())?;
    let width = grid.geometry().width();
    for (row, values) in grid.data().chunks(width).enumerate() {
        for (col, v) in values.iter().enumerate() {
            if col > 0 {
                w.write_all(b" ")?;
            }
            if grid.mask().is_valid(row * width + col) {
                write!(w, "{v}")?;
            } else {
                write!(w, "{ASC_NODATA}")?;
            }
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Writes `grid` as an ESRI ASCII grid (and a `.prj` for a WKT CRS), atomically.
pub(crate) fn write(path: &Path, grid: &Grid) -> Result<()> {
    write_atomic(path, |w| write_body(w, grid).map_err(write_err(path)))?;
    if let Some(Crs::Wkt(wkt)) = grid.geometry().crs() {
        crate::write_bytes_atomic(&path.with_extension("prj"), wkt.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(text: &str) -> Result<Grid> {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.asc");
        std::fs::write(&p, text).unwrap();
        read(&p, &ReadOptions::default())
    }

    #[test]
    fn wrapped_values_and_case_insensitive_keys() {
        let g =
            read_text("NCOLS 3\nnRows 2\nXLLCENTER 10\nyllcenter 20\nCellSize 2\n1 2\n3\n4 5 6\n")
                .unwrap();
        assert_eq!(g.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let t = g.geometry().transform();
        assert_eq!((t.origin_x, t.origin_y), (9.0, 23.0));
        assert_eq!(g.geometry().cell_size_x(), 2.0);
    }

    #[test]
    fn byte_order_mark_and_crlf() {
        let g = read_text(
            "\u{feff}ncols 2\r\nnrows 1\r\nxllcorner 0\r\nyllcorner 0\r\ncellsize 1\r\n4 5\r\n",
        )
        .unwrap();
        assert_eq!(g.data(), &[4.0, 5.0]);
    }

    #[test]
    fn dx_dy_and_nodata() {
        let g = read_text(
            "ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ndx 2\ndy 3\nnodata_value -1\n-1 7\n",
        )
        .unwrap();
        assert_eq!(g.geometry().cell_size_x(), 2.0);
        assert_eq!(g.geometry().cell_size_y(), 3.0);
        assert_eq!(g.get(0, 0), None);
        assert_eq!(g.get(1, 0), Some(7.0));
    }

    #[test]
    fn missing_key_and_bad_token_name_the_line() {
        let e = read_text("ncols 2\nnrows 1\nxllcorner 0\ncellsize 1\n1 2\n").unwrap_err();
        assert!(matches!(e, RasterError::AscMissingKey { key, .. } if key.starts_with("yll")));
        let e = read_text("ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2,5\n")
            .unwrap_err();
        assert!(
            matches!(&e, RasterError::AscToken { line: 6, token, .. } if token == "2,5"),
            "{e}"
        );
        let e = read_text("ncols 2\nnrows x\n").unwrap_err();
        assert!(matches!(&e, RasterError::AscHeader { line: 2, .. }), "{e}");
        assert!(e.to_string().contains("t.asc:2"), "{e}");
    }

    #[test]
    fn header_only_is_a_count_error() {
        let e = read_text("ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n").unwrap_err();
        assert!(matches!(
            e,
            RasterError::AscValueCount {
                found: 0,
                expected: 2,
                ..
            }
        ));
    }
}

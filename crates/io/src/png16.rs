//! 16-bit grayscale PNG heightmaps (`.png`), read and write, with the `image` crate.
//!
//! PNG (ISO/IEC 15948) stores unsigned codes; the height scale is described in
//! [`crate::heightmap16`]: `--height-range` and `--cell-size` when reading a foreign file,
//! or the `<file>.json` sidecar snowscape writes next to its own. 16-bit grayscale is the
//! heightmap format of Unreal, Unity, Gaea and World Machine; 8-bit grayscale is accepted
//! too, its 0..255 codes spread over the same height range. Any other colour type is an
//! error naming it. Nodata: only the sidecar can declare it (code 0).

use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cells};
use crate::error::{RasterError, Result, io_err};
use crate::heightmap16::{
    Png16Scale, read_sidecar, resolve_geometry, resolve_scale, write_sidecar,
};
use crate::write_atomic;
use image::codecs::png::PngEncoder;
use image::{
    DynamicImage, ExtendedColorType, ImageDecoder, ImageEncoder, ImageFormat, ImageReader,
};
use snowscape_terrain::Grid;
use std::io::BufReader;
use std::path::Path;

fn png_err(path: &Path) -> impl FnOnce(image::ImageError) -> RasterError + '_ {
    move |source| RasterError::Png {
        path: path.to_path_buf(),
        source,
    }
}

/// Reads the IHDR chunk and, before the decoder sees the file, checks the cell count and
/// that the decoded image (a filter byte and `width x bytes per pixel` per row) can come out
/// of the file's bytes (zlib expands at most 1032:1); returns decoder limits sized to the
/// image (and 1 MiB for the decoder's own buffers and text chunks). A file that does not
/// start with a PNG signature and IHDR is left to the decoder to refuse.
fn precheck(
    path: &Path,
    file: &mut std::fs::File,
    len: u64,
    max_cells: usize,
) -> Result<image::Limits> {
    use std::io::{Read, Seek, SeekFrom};
    let mut head = [0u8; 29];
    let got = file.read(&mut head).map_err(io_err(path))?;
    file.seek(SeekFrom::Start(0)).map_err(io_err(path))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(1 << 20);
    if got < 29 || &head[12..16] != b"IHDR" {
        return Ok(limits);
    }
    let be = |i: usize| u32::from_be_bytes([head[i], head[i + 1], head[i + 2], head[i + 3]]);
    let (w, h, depth, color) = (be(16), be(20), head[24], head[25]);
    check_cells(path, u64::from(w), u64::from(h), max_cells)?;
    let channels: u64 = match color {
        0 => 1,
        2 => 3,
        3 => 1,
        4 => 2,
        6 => 4,
        _ => 4,
    };
    let row = (u64::from(w) * channels * u64::from(depth.clamp(1, 16))).div_ceil(8) + 1;
    let decoded = row.saturating_mul(u64::from(h));
    if decoded > len.saturating_mul(1032) {
        return Err(RasterError::DecodedSize {
            path: path.to_path_buf(),
            what: format!("the {w}x{h} image"),
            decoded,
            stored: len,
            compression: "zlib",
            ratio: 1032,
        });
    }
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // The decoded pixels, a copy while 8-bit codes widen to 16 bits, and the decoder's buffers.
    let budget = decoded.saturating_mul(2).saturating_add(1 << 20);
    limits.max_alloc = Some(budget);
    Ok(limits)
}

/// Decodes the grayscale codes and their top code (65535 or 255), checking the cell count
/// before the pixels are decoded.
fn decode_codes(path: &Path, max_cells: usize) -> Result<(usize, usize, Vec<u16>, u16)> {
    let (mut file, len) = crate::input::open_regular(path)?;
    let limits = precheck(path, &mut file, len, max_cells)?;
    let mut reader = ImageReader::with_format(BufReader::new(file), ImageFormat::Png);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(png_err(path))?;
    let (w, h) = decoder.dimensions();
    check_cells(path, u64::from(w), u64::from(h), max_cells)?;
    let color = decoder.color_type();
    let image = match color {
        image::ColorType::L16 | image::ColorType::L8 => {
            DynamicImage::from_decoder(decoder).map_err(png_err(path))?
        }
        other => {
            return Err(RasterError::PngColor {
                path: path.to_path_buf(),
                color: format!("{other:?}"),
            });
        }
    };
    let (codes, top) = match image {
        DynamicImage::ImageLuma8(img) => (img.into_raw().into_iter().map(u16::from).collect(), 255),
        other => (other.into_luma16().into_raw(), u16::MAX),
    };
    Ok((w as usize, h as usize, codes, top))
}

/// Reads a grayscale PNG heightmap.
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    let (w, h, codes, top) = decode_codes(path, opts.max_cells)?;
    let need_sidecar = opts.height_range.is_none() || opts.cell_size.is_none();
    let sidecar = if need_sidecar {
        read_sidecar(path)?
    } else {
        None
    };
    let scale = resolve_scale(path, "16-bit PNG", opts, sidecar.as_ref())?;
    let geometry = resolve_geometry(path, "16-bit PNG", (w, h), opts, sidecar.as_ref())?;
    let mut sink = CellSink::new(path, w, h, NodataRule::declared(None));
    for code in codes {
        if Some(code) == scale.nodata {
            sink.push_nodata();
        } else {
            sink.push_f64(scale.height(code, top))?;
        }
    }
    sink.finish(geometry)
}

/// Encodes `pixels` (native-endian bytes of `color`) as a PNG at `path`, atomically.
pub(crate) fn write_png_pixels(
    path: &Path,
    (w, h): (usize, usize),
    pixels: &[u8],
    color: ExtendedColorType,
) -> Result<()> {
    let too_big = || RasterError::UnsupportedOperation {
        path: path.to_path_buf(),
        format: "PNG",
        what: "wider or taller than 2^31 pixels",
    };
    let w = u32::try_from(w).map_err(|_| too_big())?;
    let h = u32::try_from(h).map_err(|_| too_big())?;
    write_atomic(path, |out| {
        PngEncoder::new(out)
            .write_image(pixels, w, h, color)
            .map_err(png_err(path))
    })
}

/// Writes `grid` as a 16-bit grayscale PNG spanning its value range, and the JSON sidecar
/// `<path>.json` with the scale and georeferencing (see [`crate::heightmap16`]), both
/// atomically. Nodata cells are code 0 and valid heights 1..=65535 when the grid has nodata;
/// otherwise heights use 0..=65535. Returns the scale.
pub fn write_png16(path: &Path, grid: &Grid) -> Result<Png16Scale> {
    let scale = Png16Scale::for_grid(grid);
    let bytes: Vec<u8> = scale
        .encode(grid)
        .iter()
        .flat_map(|c| c.to_ne_bytes())
        .collect();
    let g = grid.geometry();
    write_png_pixels(
        path,
        (g.width(), g.height()),
        &bytes,
        ExtendedColorType::L16,
    )?;
    write_sidecar(path, &scale, g)?;
    Ok(scale)
}

//! Crafted hostile rasters and a reader for them, for `scripts/reader-limits.sh`, which runs
//! each read under `ulimit -v` (issue 46: a 17 KB deflate GeoTIFF used to abort
//! `snowscape run` allocating gigabytes).
//!
//! `reader_limits craft DIR` writes the files (a 16384² and a 20000² f32 deflate bomb of a
//! few KB, a BigTIFF whose strip offset is 2^64 - 616, a TIFF tag of 2^31 values, a PNG
//! claiming 16384² 16-bit pixels, an EXR chunk offset past the end, an NPY claiming 2^28
//! cells, an ESRI ASCII line of 8 MiB). `reader_limits read FILE [MAX_CELLS]` reads one with
//! `read_dem` and exits 0 when it reads, 2 when it is refused with a typed error (printed),
//! so a panic (101) or an allocation abort (134) or a kill (137) stands out.

#[path = "../tests/common/craft.rs"]
mod craft;

use snowscape_io::{RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape_terrain::{Grid, GridGeometry};
use std::path::Path;

fn craft_all(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let w = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes);
    w("bomb16k.tif", &craft::deflate_bomb_tiff(16384, 16384, 64))?;
    w("bomb20k.tif", &craft::deflate_bomb_tiff(20000, 20000, 100))?;
    w("bigtiff_far.tif", &craft::bigtiff_u8(Some(u64::MAX - 615)))?;
    w("tag.tif", &craft::tiff_huge_tag(1 << 31))?;
    w("bomb.png", &craft::png_bomb(16384, 16384))?;
    w("big.npy", &craft::npy_claiming(16384, 16384))?;
    w("long.asc", &craft::asc_long_line(8 << 20))?;
    let g = Grid::from_fn(GridGeometry::square(40, 30, 1.0).unwrap(), |c, r| {
        (c + r) as f32
    });
    let valid = dir.join("valid.exr");
    write_raster(&valid, &g, RasterFormat::Exr).expect("write the EXR seed");
    let bytes = std::fs::read(&valid)?;
    std::fs::remove_file(&valid)?;
    w("far.exr", &craft::exr_with_offset(bytes, u64::MAX - 999))?;
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("craft") if args.len() == 3 => {
            craft_all(Path::new(&args[2])).expect("write the crafted files");
        }
        Some("read") if args.len() >= 3 => {
            let mut opts = ReadOptions {
                cell_size: Some(1.0),
                height_range: Some((0.0, 100.0)),
                ..ReadOptions::default()
            };
            if let Some(m) = args.get(3) {
                opts.max_cells = m.parse().expect("MAX_CELLS is a whole number");
            }
            match read_dem(Path::new(&args[2]), &opts) {
                Ok(g) => {
                    let geo = g.geometry();
                    println!("read {}x{}", geo.width(), geo.height());
                }
                Err(e) => {
                    println!("refused: {e}");
                    std::process::exit(2);
                }
            }
        }
        _ => {
            eprintln!("usage: reader_limits craft DIR | reader_limits read FILE [MAX_CELLS]");
            std::process::exit(64);
        }
    }
}

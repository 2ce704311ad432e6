//! Write-then-read round trips for every format, and TIFF layouts written by the `tiff`
//! encoder or by hand (tiles, planar bands) read back exactly.

mod common;

use common::*;
use snowscape_io::{
    RasterError, RasterFormat, ReadOptions, read_dem, write_exr, write_geotiff,
    write_geotiff_bands, write_png16, write_raster, write_splat,
};
use snowscape_terrain::{Crs, LayeredTerrain, SnowLayer};
use std::io::Cursor;
use tiff::encoder::{Compression, DeflateLevel, Predictor, TiffEncoder, colortype};
use tiff::tags::Tag;

fn opts() -> ReadOptions {
    ReadOptions::default()
}

#[test]
fn geotiff_keeps_values_nodata_georef_and_crs() {
    let d = tempfile::tempdir().unwrap();
    for crs in [
        Some(Crs::Epsg(31287)),
        Some(Crs::Wkt(
            "PROJCS[\"local lambert\",UNIT[\"metre\",1]]".to_string(),
        )),
        None,
    ] {
        let g = sample_grid(37, 23, crs.clone(), true);
        let p = d.path().join("a.tif");
        write_geotiff(&p, &g).unwrap();
        let r = read_dem(&p, &opts()).unwrap();
        assert_same_cells(&g, &r, 0.0);
        assert_eq!(r.geometry(), g.geometry());
        assert_eq!(r.geometry().crs(), crs.as_ref());
    }
}

#[test]
fn geotiff_in_degrees_keeps_metric_cells() {
    let d = tempfile::tempdir().unwrap();
    let g = degree_grid(30, 20);
    let p = d.path().join("deg.tif");
    write_geotiff(&p, &g).unwrap();
    let r = read_dem(&p, &opts()).unwrap();
    assert_eq!(r.geometry(), g.geometry());
    assert!((r.geometry().cell_size_y() - 92.5).abs() < 1.0);
    assert_eq!(r.data(), g.data());
}

#[test]
fn geotiff_bands_are_interleaved_and_band_1_is_the_dem() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(19, 11, Some(Crs::Epsg(32611)), true);
    let u: Vec<f32> = (0..g.data().len()).map(|i| i as f32).collect();
    let v: Vec<f32> = (0..g.data().len()).map(|i| -(i as f32)).collect();
    let p = d.path().join("wind.tif");
    write_geotiff_bands(&p, g.geometry(), g.mask(), &[&u, &v]).unwrap();
    let r = read_dem(&p, &opts()).unwrap();
    assert_eq!(r.mask(), g.mask());
    for (i, (got, want)) in r.data().iter().zip(&u).enumerate() {
        if g.mask().is_valid(i) {
            assert_eq!(got, want);
        }
    }
    // Decode directly: two f32 samples per pixel, nodata -9999 in both bands.
    let mut dec = tiff::decoder::Decoder::new(std::fs::File::open(&p).unwrap()).unwrap();
    assert_eq!(
        dec.get_tag_u32(Tag::SamplesPerPixel).unwrap(),
        2,
        "two bands"
    );
    assert_eq!(dec.get_tag_ascii_string(Tag::GdalNodata).unwrap(), "-9999");
    let tiff::decoder::DecodingResult::F32(s) = dec.read_image().unwrap() else {
        panic!("f32 expected")
    };
    assert_eq!(s.len(), 2 * u.len());
    assert_eq!(s[2 * 5 + 1], v[5]);
    assert_eq!((s[0], s[1]), (-9999.0, -9999.0), "cell 0 is nodata");
    let e = write_geotiff_bands(&p, g.geometry(), g.mask(), &[&u, &v[1..]]).unwrap_err();
    assert!(matches!(e, RasterError::LengthMismatch { found, .. } if found == v.len() - 1));
}

/// A TIFF written with the `tiff` encoder: `data` as colour type `C`, ModelPixelScale and
/// ModelTiepoint, optional GDAL_NODATA.
fn encode<C: colortype::ColorType>(
    data: &[C::Inner],
    (w, h): (u32, u32),
    compression: Compression,
    predictor: Predictor,
    nodata: Option<&str>,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut buf = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut buf)
        .unwrap()
        .with_compression(compression)
        .with_predictor(predictor);
    let mut img = enc.new_image::<C>(w, h).unwrap();
    img.encoder()
        .write_tag(Tag::ModelPixelScaleTag, &[2.0f64, 2.0, 0.0][..])
        .unwrap();
    img.encoder()
        .write_tag(
            Tag::ModelTiepointTag,
            &[0.0f64, 0.0, 0.0, 500.0, 900.0, 0.0][..],
        )
        .unwrap();
    if let Some(n) = nodata {
        img.encoder().write_tag(Tag::GdalNodata, n).unwrap();
    }
    img.write_data(data).unwrap();
    buf.into_inner()
}

fn read_bytes(
    bytes: &[u8],
    name: &str,
    o: &ReadOptions,
) -> Result<snowscape_terrain::Grid, RasterError> {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    read_dem(&p, o)
}

#[test]
fn tiff_sample_formats_and_compressions_read_back() {
    let (w, h) = (33u32, 17u32);
    let n = (w * h) as usize;
    let compressions = [
        Compression::Uncompressed,
        Compression::Lzw,
        Compression::Deflate(DeflateLevel::Balanced),
        Compression::Packbits,
    ];
    for comp in compressions {
        let int_pred = if comp == Compression::Lzw {
            Predictor::Horizontal
        } else {
            Predictor::None
        };
        let u16s: Vec<u16> = (0..n).map(|i| (i * 37 % 60000) as u16).collect();
        let i16s: Vec<i16> = (0..n).map(|i| (i as i16).wrapping_mul(7) - 300).collect();
        let i32s: Vec<i32> = (0..n).map(|i| i as i32 * 1000 - 70_000).collect();
        let u8s: Vec<u8> = (0..n).map(|i| (i % 251) as u8).collect();
        let f32s: Vec<f32> = (0..n).map(|i| i as f32 * 0.25 - 3.0).collect();
        let f64s: Vec<f64> = (0..n).map(|i| i as f64 * 0.5 + 1e3).collect();
        let cases: Vec<(Vec<u8>, Vec<f32>)> = vec![
            (
                encode::<colortype::Gray16>(&u16s, (w, h), comp, int_pred, None),
                u16s.iter().map(|&v| f32::from(v)).collect(),
            ),
            (
                encode::<colortype::GrayI16>(&i16s, (w, h), comp, int_pred, None),
                i16s.iter().map(|&v| f32::from(v)).collect(),
            ),
            (
                encode::<colortype::GrayI32>(&i32s, (w, h), comp, int_pred, None),
                i32s.iter().map(|&v| v as f32).collect(),
            ),
            (
                encode::<colortype::Gray8>(&u8s, (w, h), comp, int_pred, None),
                u8s.iter().map(|&v| f32::from(v)).collect(),
            ),
            (
                encode::<colortype::Gray32Float>(&f32s, (w, h), comp, Predictor::None, None),
                f32s.clone(),
            ),
            (
                encode::<colortype::Gray64Float>(&f64s, (w, h), comp, Predictor::None, None),
                f64s.iter().map(|&v| v as f32).collect(),
            ),
        ];
        for (k, (bytes, want)) in cases.iter().enumerate() {
            let g = read_bytes(bytes, "s.tif", &opts()).unwrap_or_else(|e| panic!("case {k}: {e}"));
            assert_eq!(g.data(), &want[..], "case {k} compression {}", k);
            assert_eq!(g.geometry().cell_size_x(), 2.0);
            assert_eq!(g.geometry().transform().origin_y, 900.0);
        }
    }
}

#[test]
fn tiff_nodata_rule() {
    let (w, h) = (4u32, 2u32);
    let mut f = vec![1.0f32; 8];
    f[1] = f32::NAN;
    f[2] = -32768.0;
    // No GDAL_NODATA: NaN is nodata.
    let b = encode::<colortype::Gray32Float>(
        &f,
        (w, h),
        Compression::Uncompressed,
        Predictor::None,
        None,
    );
    let g = read_bytes(&b, "n.tif", &opts()).unwrap();
    assert_eq!(g.mask().count_nodata(), 1);
    assert_eq!(g.get(2, 0), Some(-32768.0));
    // Declared nodata: that value is nodata and NaN is an error naming the cell.
    let b = encode::<colortype::Gray32Float>(
        &f,
        (w, h),
        Compression::Uncompressed,
        Predictor::None,
        Some("-32768"),
    );
    let e = read_bytes(&b, "n.tif", &opts()).unwrap_err();
    assert!(
        matches!(e, RasterError::NonFinite { col: 1, row: 0, .. }),
        "{e}"
    );
    f[1] = 5.0;
    let b = encode::<colortype::Gray32Float>(
        &f,
        (w, h),
        Compression::Uncompressed,
        Predictor::None,
        Some(" -32768 "),
    );
    let g = read_bytes(&b, "n.tif", &opts()).unwrap();
    assert_eq!(g.get(2, 0), None);
    // Infinity is always an error.
    f[7] = f32::INFINITY;
    let b = encode::<colortype::Gray32Float>(
        &f,
        (w, h),
        Compression::Uncompressed,
        Predictor::None,
        None,
    );
    let e = read_bytes(&b, "inf.tif", &opts()).unwrap_err();
    assert!(
        matches!(e, RasterError::NonFinite { col: 3, row: 1, .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains("inf.tif") && e.to_string().contains("inf"),
        "{e}"
    );
    // Integer nodata (the earthpy convention).
    let u = vec![65535u16, 2000, 2001, 65535];
    let b = encode::<colortype::Gray16>(
        &u,
        (2, 2),
        Compression::Lzw,
        Predictor::Horizontal,
        Some("65535"),
    );
    let g = read_bytes(&b, "u.tif", &opts()).unwrap();
    assert_eq!(g.mask().count_nodata(), 2);
    assert_eq!(g.value_range(), Some((2000.0, 2001.0)));
    let b =
        encode::<colortype::Gray16>(&u, (2, 2), Compression::Lzw, Predictor::None, Some("none"));
    let e = read_bytes(&b, "u.tif", &opts()).unwrap_err();
    assert!(
        matches!(&e, RasterError::GeoTiffTag { tag: 42113, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("\"none\""), "{e}");
}

fn band(w: u32, h: u32, k: u16) -> Vec<u16> {
    (0..w * h)
        .map(|i| (i as u16).wrapping_mul(3).wrapping_add(k * 1000))
        .collect()
}

#[test]
fn tiled_planar_and_interleaved_tiffs_give_band_1() {
    let (w, h) = (40, 23);
    for (tile, planar, nbands) in [
        (Some(16), false, 1),
        (Some(16), true, 2),
        (None, true, 3),
        (None, false, 3),
        (Some(32), false, 2),
    ] {
        let t = HandTiff {
            w,
            h,
            bands: (0..nbands).map(|k| band(w, h, k)).collect(),
            tile,
            rows_per_strip: 5,
            planar,
            extra: vec![],
        };
        let o = ReadOptions {
            cell_size: Some(3.0),
            ..opts()
        };
        let g = read_bytes(&t.bytes(), "hand.tif", &o)
            .unwrap_or_else(|e| panic!("{tile:?} {planar} {nbands}: {e}"));
        let want: Vec<f32> = band(w, h, 0).iter().map(|&v| f32::from(v)).collect();
        assert_eq!(
            g.data(),
            &want[..],
            "{tile:?} planar {planar} bands {nbands}"
        );
        assert_eq!(g.geometry().cell_size_x(), 3.0);
    }
}

#[test]
fn tiff_without_georef_needs_cell_size() {
    let t = HandTiff {
        w: 4,
        h: 3,
        bands: vec![band(4, 3, 0)],
        tile: None,
        rows_per_strip: 3,
        planar: false,
        extra: vec![],
    };
    let e = read_bytes(&t.bytes(), "plain.tif", &opts()).unwrap_err();
    assert!(
        matches!(
            e,
            RasterError::MissingOption {
                option: "--cell-size",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn pixel_is_point_and_model_transformation() {
    let base = |extra| HandTiff {
        w: 4,
        h: 3,
        bands: vec![band(4, 3, 0)],
        tile: None,
        rows_per_strip: 3,
        planar: false,
        extra,
    };
    // PixelIsPoint: the tiepoint is a cell centre, the corner half a cell up-left.
    let t = base(vec![
        f64_entry(33550, &[10.0, 20.0, 0.0]),
        f64_entry(33922, &[0.0, 0.0, 0.0, 1000.0, 5000.0, 0.0]),
        u16_entry(34735, &[1, 1, 0, 2, 1025, 0, 1, 2, 3072, 0, 1, 32633]),
    ]);
    let g = read_bytes(&t.bytes(), "pt.tif", &opts()).unwrap();
    let tr = g.geometry().transform();
    assert_eq!((tr.origin_x, tr.origin_y), (995.0, 5010.0));
    assert_eq!(g.geometry().crs(), Some(&Crs::Epsg(32633)));
    // ModelTransformation with a tiepoint not at (0, 0) elsewhere.
    let m = [
        2.5, 0.0, 0.0, 300.0, 0.0, -4.0, 0.0, 800.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let g = read_bytes(&base(vec![f64_entry(34264, &m)]).bytes(), "m.tif", &opts()).unwrap();
    let tr = g.geometry().transform();
    assert_eq!(
        (tr.origin_x, tr.origin_y, tr.pixel_width, tr.pixel_height),
        (300.0, 800.0, 2.5, 4.0)
    );
    let mut rot = m;
    rot[1] = 0.5;
    let e = read_bytes(
        &base(vec![f64_entry(34264, &rot)]).bytes(),
        "r.tif",
        &opts(),
    )
    .unwrap_err();
    assert!(
        matches!(e, RasterError::GeoTiffTag { tag: 34264, .. }),
        "{e}"
    );
    // A tiepoint at pixel (2, 1).
    let t = base(vec![
        f64_entry(33550, &[10.0, 10.0, 0.0]),
        f64_entry(33922, &[2.0, 1.0, 0.0, 1000.0, 5000.0, 0.0]),
    ]);
    let g = read_bytes(&t.bytes(), "tp.tif", &opts()).unwrap();
    let tr = g.geometry().transform();
    assert_eq!((tr.origin_x, tr.origin_y), (980.0, 5010.0));
    // Zero pixel scale names the tag.
    let t = base(vec![
        f64_entry(33550, &[0.0, 10.0, 0.0]),
        f64_entry(33922, &[0.0, 0.0, 0.0, 1000.0, 5000.0, 0.0]),
    ]);
    let e = read_bytes(&t.bytes(), "z.tif", &opts()).unwrap_err();
    assert!(
        matches!(&e, RasterError::InvalidCellSize { value, source_of, .. } if *value == 0.0 && source_of.contains("33550")),
        "{e}"
    );
}

#[test]
fn asc_round_trip_with_nodata_and_rectangular_cells() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(21, 13, None, true);
    let p = d.path().join("g.asc");
    write_raster(&p, &g, RasterFormat::Asc).unwrap();
    let r = read_dem(&p, &opts()).unwrap();
    assert_same_cells(&g, &r, 0.0);
    assert_eq!(r.geometry(), g.geometry());
    // A WKT CRS travels in a .prj sidecar.
    let wkt = Crs::Wkt("PROJCS[\"x\",UNIT[\"metre\",1]]".into());
    let g = sample_grid(5, 4, Some(wkt.clone()), false);
    write_raster(&p, &g, RasterFormat::Asc).unwrap();
    assert_eq!(read_dem(&p, &opts()).unwrap().geometry().crs(), Some(&wkt));
}

#[test]
fn png16_round_trip_through_the_sidecar() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(31, 17, Some(Crs::Epsg(31287)), true);
    let p = d.path().join("h.png");
    let scale = write_png16(&p, &g).unwrap();
    let (lo, hi) = g.value_range().unwrap();
    assert_eq!(
        (scale.min, scale.max, scale.nodata),
        (f64::from(lo), f64::from(hi), Some(0))
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join("h.png.json")).unwrap())
            .unwrap();
    assert_eq!(json["nodata"], 0);
    assert_eq!(json["unit"], "m");
    assert_eq!(json["min"], f64::from(lo));
    let r = read_dem(&p, &opts()).unwrap();
    let step = (hi - lo) / 65534.0;
    assert_same_cells(&g, &r, step);
    assert_eq!(r.geometry(), g.geometry());
    // Explicit options win over the sidecar; without both, a clear error.
    let o = ReadOptions {
        height_range: Some((0.0, 65535.0)),
        cell_size: Some(2.0),
        ..opts()
    };
    let r = read_dem(&p, &o).unwrap();
    assert_eq!(r.geometry().cell_size_x(), 2.0);
    std::fs::remove_file(d.path().join("h.png.json")).unwrap();
    let e = read_dem(&p, &opts()).unwrap_err();
    assert!(
        matches!(e, RasterError::MissingOption { option, .. } if option.contains("--height-range"))
    );
    let e = read_dem(
        &p,
        &ReadOptions {
            height_range: Some((0.0, 1.0)),
            ..opts()
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("--cell-size") && e.to_string().contains("h.png"),
        "{e}"
    );
}

#[test]
fn png8_uses_0_to_255() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("g8.png");
    let img = image::GrayImage::from_raw(2, 1, vec![0, 255]).unwrap();
    img.save(&p).unwrap();
    let o = ReadOptions {
        height_range: Some((100.0, 610.0)),
        cell_size: Some(1.0),
        ..opts()
    };
    assert_eq!(read_dem(&p, &o).unwrap().data(), &[100.0, 610.0]);
    let rgb = image::RgbImage::new(2, 2);
    rgb.save(&p).unwrap();
    let e = read_dem(&p, &o).unwrap_err();
    assert!(
        matches!(&e, RasterError::PngColor { color, .. } if color.contains("Rgb8")),
        "{e}"
    );
}

#[test]
fn raw16_round_trip_and_square_inference() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(16, 9, None, false);
    let p = d.path().join("h.r16");
    write_raster(&p, &g, RasterFormat::Raw16).unwrap();
    assert_eq!(std::fs::metadata(&p).unwrap().len(), 2 * 16 * 9);
    let r = read_dem(&p, &opts()).unwrap();
    let (lo, hi) = g.value_range().unwrap();
    assert_same_cells(&g, &r, (hi - lo) / 65535.0);
    // Without a sidecar: a square from the length, or an error naming the byte count.
    let q = d.path().join("sq.raw");
    let codes: Vec<u8> = (0..9u16).flat_map(|v| (v * 1000).to_le_bytes()).collect();
    std::fs::write(&q, &codes).unwrap();
    let o = ReadOptions {
        height_range: Some((0.0, 65535.0)),
        cell_size: Some(1.0),
        ..opts()
    };
    let r = read_dem(&q, &o).unwrap();
    assert_eq!((r.geometry().width(), r.geometry().height()), (3, 3));
    assert_eq!(r.get(2, 0), Some(2000.0));
    std::fs::write(&q, &codes[..16]).unwrap();
    let e = read_dem(&q, &o).unwrap_err();
    assert!(matches!(e, RasterError::RawSize { bytes: 16, .. }), "{e}");
    assert!(e.to_string().contains("16 bytes"));
    let e = read_dem(
        &q,
        &ReadOptions {
            raw_size: Some((3, 3)),
            ..o.clone()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("18"), "{e}");
    let r = read_dem(
        &q,
        &ReadOptions {
            raw_size: Some((4, 2)),
            ..o
        },
    )
    .unwrap();
    assert_eq!(r.geometry().width(), 4);
}

#[test]
fn npy_round_trip_nan_nodata_and_fortran_order() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(12, 7, None, true);
    let p = d.path().join("a.npy");
    write_raster(&p, &g, RasterFormat::Npy).unwrap();
    let e = read_dem(&p, &opts()).unwrap_err();
    assert!(matches!(
        e,
        RasterError::MissingOption {
            option: "--cell-size",
            ..
        }
    ));
    let o = ReadOptions {
        cell_size: Some(5.0),
        ..opts()
    };
    let r = read_dem(&p, &o).unwrap();
    assert_same_cells(&g, &r, 0.0);
    // A Fortran-order i16 array (3 rows, 2 cols) written column by column.
    let f = d.path().join("f.npy");
    let mut buf = Vec::new();
    {
        use npyz::WriterBuilder;
        let mut w = npyz::WriteOptions::<i16>::new()
            .default_dtype()
            .shape(&[3, 2])
            .order(npyz::Order::Fortran)
            .writer(&mut buf)
            .begin_nd()
            .unwrap();
        for v in [1i16, 2, 3, 10, 20, 30] {
            w.push(&v).unwrap();
        }
        w.finish().unwrap();
    }
    std::fs::write(&f, &buf).unwrap();
    let r = read_dem(&f, &o).unwrap();
    assert_eq!(r.data(), &[1.0, 10.0, 2.0, 20.0, 3.0, 30.0]);
}

#[test]
fn exr_channels_are_readable_by_the_exr_crate() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(20, 10, Some(Crs::Epsg(31287)), false);
    let a: Vec<f32> = (0..200).map(|i| i as f32 * 0.5).collect();
    let b: Vec<f32> = (0..200).map(|i| -(i as f32)).collect();
    let p = d.path().join("layers.exr");
    write_exr(&p, g.geometry(), &[("powder", &a), ("height", &b)]).unwrap();
    let img = exr::prelude::read_all_flat_layers_from_file(&p).unwrap();
    let layer = &img.layer_data[0];
    assert_eq!((layer.size.0, layer.size.1), (20, 10));
    let names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    assert_eq!(names, ["height", "powder"]);
    let powder: Vec<f32> = layer.channel_data.list[1]
        .sample_data
        .values_as_f32()
        .collect();
    assert_eq!(powder, a);
    // read_dem picks the "height" channel and the georeferencing attributes.
    let r = read_dem(&p, &opts()).unwrap();
    assert_eq!(r.data(), &b[..]);
    assert_eq!(r.geometry(), g.geometry());
    // Same input, same bytes (the georeferencing is one attribute, so no map order leaks in).
    let q = d.path().join("again.exr");
    for _ in 0..4 {
        write_exr(&q, g.geometry(), &[("powder", &a), ("height", &b)]).unwrap();
        assert!(std::fs::read(&q).unwrap() == std::fs::read(&p).unwrap());
    }
    let e = write_exr(&p, g.geometry(), &[("a", &a), ("a", &b)]).unwrap_err();
    assert!(e.to_string().contains("twice"), "{e}");
}

#[test]
fn exr_nodata_is_nan() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(9, 6, None, true);
    let p = d.path().join("g.exr");
    write_raster(&p, &g, RasterFormat::Exr).unwrap();
    let r = read_dem(&p, &opts()).unwrap();
    assert_same_cells(&g, &r, 0.0);
}

#[test]
fn splat_channels_are_layer_shares() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(4, 3, None, true);
    let mut t = LayeredTerrain::from_bedrock(g);
    // Cell (1, 0): compacted 1, powder 3; cell (2, 0): no snow; cell (0, 0): nodata.
    t.layer_mut(SnowLayer::Compacted)[1] = 1.0;
    t.layer_mut(SnowLayer::Powder)[1] = 3.0;
    t.layer_mut(SnowLayer::Stable)[3] = 0.5;
    t.layer_mut(SnowLayer::Unstable)[3] = 0.5;
    let p = d.path().join("splat.png");
    write_splat(&p, &t).unwrap();
    let img = image::open(&p).unwrap().into_rgba8();
    assert_eq!(img.dimensions(), (4, 3));
    assert_eq!(img.get_pixel(1, 0).0, [64, 0, 0, 191]);
    assert_eq!(img.get_pixel(2, 0).0, [0, 0, 0, 0]);
    assert_eq!(img.get_pixel(3, 0).0, [0, 128, 128, 0]);
}

#[test]
fn every_format_round_trips_through_write_raster() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(10, 8, None, true);
    let o = ReadOptions {
        cell_size: Some(5.0),
        ..opts()
    };
    for f in RasterFormat::ALL {
        let p = d.path().join(format!("x.{}", f.extension()));
        write_raster(&p, &g, f).unwrap();
        let r = read_dem(&p, &o).unwrap_or_else(|e| panic!("{f}: {e}"));
        let (lo, hi) = g.value_range().unwrap();
        let tol = if matches!(f, RasterFormat::Png16 | RasterFormat::Raw16) {
            (hi - lo) / 65534.0
        } else {
            0.0
        };
        assert_same_cells(&g, &r, tol);
    }
}

#[test]
fn forced_format_overrides_the_extension() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(6, 5, None, false);
    let p = d.path().join("dem.data");
    write_raster(&p, &g, RasterFormat::GeoTiff).unwrap();
    let e = read_dem(&p, &opts()).unwrap_err();
    assert!(matches!(&e, RasterError::UnknownFormat { extension, .. } if extension == "data"));
    let o = ReadOptions {
        format: Some(RasterFormat::GeoTiff),
        ..opts()
    };
    assert_eq!(read_dem(&p, &o).unwrap().data(), g.data());
}

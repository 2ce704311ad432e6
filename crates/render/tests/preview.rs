//! Behaviour of the previews: lighting, snow, stability colours, nodata, downsampling, maps.

use image::RgbaImage;
use snowscape_render::{
    ColourMode, PreviewOptions, RenderError, render_dem, render_preview, stability_colour,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

fn terrain(w: usize, h: usize, cell: f64, z: impl FnMut(usize, usize) -> f32) -> LayeredTerrain {
    let g = GridGeometry::square(w, h, cell).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, z))
}

fn rgb(img: &RgbaImage, x: u32, y: u32) -> [u8; 4] {
    img.get_pixel(x, y).0
}

fn brightness(px: [u8; 4]) -> u32 {
    px[0] as u32 + px[1] as u32 + px[2] as u32
}

/// 2D gradient (Perlin) noise, roughly in [-1, 1], with splitmix64-hashed lattice gradients.
fn gradient_noise(x: f32, y: f32, seed: u64) -> f32 {
    let corner = |i: i64, j: i64, dx: f32, dy: f32| {
        let mut h =
            (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (j as u64).rotate_left(32) ^ seed;
        h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        let angle = (h >> 11) as f32 / (1u64 << 53) as f32 * std::f32::consts::TAU;
        angle.cos() * dx + angle.sin() * dy
    };
    let (i, j) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (u, v) = (fade(fx), fade(fy));
    let n00 = corner(i, j, fx, fy);
    let n10 = corner(i + 1, j, fx - 1.0, fy);
    let n01 = corner(i, j + 1, fx, fy - 1.0);
    let n11 = corner(i + 1, j + 1, fx - 1.0, fy - 1.0);
    let top = n00 + (n10 - n00) * u;
    let bottom = n01 + (n11 - n01) * u;
    1.4 * (top + (bottom - top) * v)
}

/// Musgrave's ridged multifractal of gradient noise at (x, y) in kilometres: sharp crests,
/// smooth valleys. Roughly in [0, 2].
fn ridges(x: f32, y: f32) -> f32 {
    let (mut z, mut amp, mut freq, mut weight) = (0.0f32, 1.0f32, 0.9f32, 1.0f32);
    for octave in 0..6 {
        let signal = 1.0 - gradient_noise(x * freq, y * freq, octave).abs();
        let r = signal * signal * weight;
        weight = (2.0 * r).clamp(0.0, 1.0);
        z += r * amp;
        amp *= 0.38;
        freq *= 2.0;
    }
    z
}

/// A synthetic alpine scene on a 2.56 km square: ridged mountains rising from a valley floor
/// near 900 m towards a massif in the north-west, snow above 1200 m thickening with altitude
/// and sliding off steep rock, an unstable slab on steep east-facing slopes, powder on the
/// summits, and a "sun" map growing eastwards.
fn alpine(n: usize) -> LayeredTerrain {
    let cell = 2560.0 / n as f32;
    let mut t = terrain(n, n, cell as f64, |col, row| {
        let (x, y) = (col as f32 * cell / 1000.0, row as f32 * cell / 1000.0);
        let massif = (1.0 - ((x - 0.9).powi(2) + (y - 1.0).powi(2)).sqrt() / 2.2).max(0.15);
        900.0 + 480.0 * massif * ridges(x, y)
    });
    let slopes = snowscape_terrain::surface::slopes(&t.bedrock, t.geometry(), t.mask());
    for (i, slope) in slopes.iter().map(|s| s.to_degrees()).enumerate() {
        let z = t.bedrock[i];
        let held = ((50.0 - slope) / 20.0).clamp(0.0, 1.0);
        let snow = ((z - 1200.0) / 300.0).clamp(0.0, 2.5) * held;
        let east_face = i % n > 1 && t.bedrock[i - 1] > z + 0.3 * cell && slope > 28.0;
        t.layer_mut(SnowLayer::Compacted)[i] = 0.3 * snow;
        t.layer_mut(SnowLayer::Stable)[i] = 0.7 * snow;
        if east_face && snow > 0.0 {
            t.layer_mut(SnowLayer::Unstable)[i] = 0.4;
        }
        if z > 1650.0 {
            t.layer_mut(SnowLayer::Powder)[i] = 0.2 * held;
        }
    }
    let sun: Vec<f32> = (0..n * n).map(|i| (i % n) as f32 / n as f32).collect();
    t.set_map("sun", sun).unwrap();
    t
}

#[test]
fn flat_snow_free_plane_is_uniform() {
    let t = terrain(16, 12, 10.0, |_, _| 500.0);
    let img = render_preview(&t, &PreviewOptions::default()).unwrap();
    assert_eq!(img.dimensions(), (16, 12));
    let first = rgb(&img, 0, 0);
    assert_eq!(first[3], 255);
    assert!(img.pixels().all(|p| p.0 == first), "not uniform");
}

#[test]
fn snow_is_whiter_than_bare_ground() {
    let mut t = terrain(10, 10, 5.0, |_, _| 1000.0);
    for row in 0..10 {
        for col in 5..10 {
            t.layer_mut(SnowLayer::Stable)[row * 10 + col] = 1.0;
        }
    }
    let img = render_preview(&t, &PreviewOptions::default()).unwrap();
    let (bare, snowy) = (rgb(&img, 1, 5), rgb(&img, 8, 5));
    assert!(
        brightness(snowy) > brightness(bare) + 150,
        "{bare:?} {snowy:?}"
    );
    // White: channels nearly equal.
    assert!(snowy[0].abs_diff(snowy[2]) < 25, "{snowy:?}");
}

#[test]
fn thin_snow_lets_the_ground_show_through() {
    let mut t = terrain(3, 1, 5.0, |_, _| 1000.0);
    t.layer_mut(SnowLayer::Powder)[1] = 0.03;
    t.layer_mut(SnowLayer::Powder)[2] = 1.0;
    let img = render_preview(&t, &PreviewOptions::default()).unwrap();
    let [bare, thin, deep] = [0, 1, 2].map(|x| brightness(rgb(&img, x, 0)));
    assert!(bare < thin && thin < deep, "{bare} {thin} {deep}");
}

#[test]
fn slope_facing_the_sun_is_brighter() {
    // A symmetric east-west roof: the west face looks at a western sun.
    let t = terrain(40, 10, 10.0, |col, _| {
        1000.0 - 8.0 * (col as f32 - 20.0).abs()
    });
    let opts = PreviewOptions {
        sun_azimuth_deg: 270.0,
        sun_elevation_deg: 40.0,
        ..Default::default()
    };
    let img = render_preview(&t, &opts).unwrap();
    let (west, east) = (rgb(&img, 10, 5), rgb(&img, 30, 5));
    assert!(
        brightness(west) > brightness(east) + 60,
        "{west:?} {east:?}"
    );
    // Turning the sun to the east swaps them.
    let img = render_preview(
        &t,
        &PreviewOptions {
            sun_azimuth_deg: 90.0,
            ..opts
        },
    )
    .unwrap();
    assert!(brightness(rgb(&img, 30, 5)) > brightness(rgb(&img, 10, 5)) + 60);
}

#[test]
fn a_wall_casts_a_shadow_on_the_plain_behind_it() {
    let t = terrain(60, 5, 1.0, |col, _| if col == 10 { 20.0 } else { 0.0 });
    let opts = PreviewOptions {
        sun_azimuth_deg: 270.0,
        sun_elevation_deg: 30.0,
        ..Default::default()
    };
    let img = render_preview(&t, &opts).unwrap();
    // Shadow length 20 / tan 30° ≈ 34.6 m east of the wall.
    let (shadowed, lit) = (rgb(&img, 30, 2), rgb(&img, 55, 2));
    assert!(
        brightness(lit) > brightness(shadowed) + 60,
        "{lit:?} {shadowed:?}"
    );
}

#[test]
fn nodata_is_transparent() {
    let g = GridGeometry::square(4, 4, 10.0).unwrap();
    let mut invalid = vec![false; 16];
    invalid[5] = true;
    let dem = Grid::new(g, vec![100.0; 16], NodataMask::from_invalid(invalid)).unwrap();
    let img = render_dem(&dem, &PreviewOptions::default()).unwrap();
    assert_eq!(rgb(&img, 1, 1)[3], 0);
    assert_eq!(rgb(&img, 2, 1)[3], 255);
    let t = LayeredTerrain::from_bedrock(dem);
    let img = render_preview(&t, &PreviewOptions::default()).unwrap();
    assert_eq!(rgb(&img, 1, 1)[3], 0);
    assert_eq!(rgb(&img, 0, 0)[3], 255);
}

#[test]
fn stability_mode_separates_unstable_from_stable_snow() {
    let mut t = terrain(3, 1, 10.0, |_, _| 1000.0);
    t.layer_mut(SnowLayer::Stable)[0] = 1.0;
    t.layer_mut(SnowLayer::Stable)[1] = 1.0;
    t.layer_mut(SnowLayer::Unstable)[1] = 0.5;
    let opts = PreviewOptions {
        mode: ColourMode::Stability,
        ..Default::default()
    };
    let img = render_preview(&t, &opts).unwrap();
    let (stable, unstable, bare) = (rgb(&img, 0, 0), rgb(&img, 1, 0), rgb(&img, 2, 0));
    // Fig. 11: stable blue, unstable purple (red well above green), no snow black.
    assert!(
        stable[2] > stable[0] + 80 && stable[2] > stable[1] + 40,
        "{stable:?}"
    );
    assert!(
        unstable[0] > unstable[1] + 60 && unstable[2] > unstable[1] + 60,
        "{unstable:?}"
    );
    assert_eq!(&bare[..3], &[0, 0, 0]);
    assert_ne!(stability_colour(&t, 0), stability_colour(&t, 1));
    assert_eq!(stability_colour(&t, 2), [0, 0, 0]);
    assert_eq!(stability_colour(&t, 99), [0, 0, 0]);
}

#[test]
fn layers_mode_tints_unstable_snow_warm_and_powder_cool() {
    let mut t = terrain(2, 1, 10.0, |_, _| 1000.0);
    t.layer_mut(SnowLayer::Unstable)[0] = 1.0;
    t.layer_mut(SnowLayer::Powder)[1] = 1.0;
    let opts = PreviewOptions {
        mode: ColourMode::Layers,
        ..Default::default()
    };
    let img = render_preview(&t, &opts).unwrap();
    let (unstable, powder) = (rgb(&img, 0, 0), rgb(&img, 1, 0));
    assert!(unstable[0] > unstable[2] + 80, "{unstable:?}");
    assert!(powder[2] > powder[0] + 30, "{powder:?}");
}

#[test]
fn downsampled_output_respects_max_size_and_keeps_the_aspect() {
    let t = terrain(1000, 300, 2.0, |c, r| (c + r) as f32 * 0.1);
    for max in [1, 7, 64, 256, 999, 1000, 4096] {
        let opts = PreviewOptions {
            max_size: Some(max),
            ..Default::default()
        };
        let img = render_preview(&t, &opts).unwrap();
        assert!(
            img.width().max(img.height()) as usize <= max.min(1000),
            "{max}"
        );
        let f = 1000usize.div_ceil(max);
        assert_eq!(
            img.dimensions(),
            (1000usize.div_ceil(f) as u32, 300usize.div_ceil(f) as u32)
        );
    }
    let opts = PreviewOptions {
        max_size: Some(0),
        ..Default::default()
    };
    assert!(matches!(
        render_preview(&t, &opts),
        Err(RenderError::InvalidCount {
            name: "max_size",
            ..
        })
    ));
}

#[test]
fn map_mode_ramps_the_map_and_names_missing_maps() {
    let t = alpine(64);
    let opts = PreviewOptions {
        mode: ColourMode::Map("sun".into()),
        sun_elevation_deg: 90.0,
        ..Default::default()
    };
    let img = render_preview(&t, &opts).unwrap();
    // "sun" grows eastwards: the west edge is dark purple, the east edge yellow-green.
    let (west, east) = (rgb(&img, 0, 60), rgb(&img, 63, 60));
    assert!(west[2] > west[1], "{west:?}");
    assert!(
        east[1] > east[2] && brightness(east) > brightness(west) + 150,
        "{east:?}"
    );
    let missing = PreviewOptions {
        mode: ColourMode::Map("wind".into()),
        ..Default::default()
    };
    let e = render_preview(&t, &missing).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("\"wind\"") && text.contains("sun"), "{text}");
}

#[test]
fn bad_options_are_typed_errors() {
    let t = terrain(4, 4, 1.0, |_, _| 0.0);
    for (opts, name) in [
        (
            PreviewOptions {
                sun_elevation_deg: 0.0,
                ..Default::default()
            },
            "sun_elevation_deg",
        ),
        (
            PreviewOptions {
                sun_elevation_deg: f64::NAN,
                ..Default::default()
            },
            "sun_elevation_deg",
        ),
        (
            PreviewOptions {
                sun_azimuth_deg: f64::INFINITY,
                ..Default::default()
            },
            "sun_azimuth_deg",
        ),
        (
            PreviewOptions {
                vertical_exaggeration: -1.0,
                ..Default::default()
            },
            "vertical_exaggeration",
        ),
    ] {
        match render_preview(&t, &opts) {
            Err(RenderError::InvalidOption { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    let mut broken = t.clone();
    broken.snow[2].pop();
    assert!(matches!(
        render_preview(&broken, &PreviewOptions::default()),
        Err(RenderError::LengthMismatch { .. })
    ));
}

#[test]
fn demo_previews_render_for_eyeballing() {
    let t = alpine(512);
    let dir = std::env::temp_dir().join("snowscape-render-demo");
    std::fs::create_dir_all(&dir).unwrap();
    for (mode, name) in [
        (ColourMode::Snow, "snow"),
        (ColourMode::Layers, "layers"),
        (ColourMode::Stability, "stability"),
        (ColourMode::Map("sun".into()), "map_sun"),
    ] {
        let opts = PreviewOptions {
            mode,
            ..Default::default()
        };
        let img = render_preview(&t, &opts).unwrap();
        assert!(img.pixels().all(|p| p.0[3] == 255));
        let png = snowscape_render::encode_png(&img).unwrap();
        std::fs::write(dir.join(format!("{name}.png")), png).unwrap();
    }
}

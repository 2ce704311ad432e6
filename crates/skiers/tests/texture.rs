//! The track texture: anti-aliased coverage, sparse tiles, fading under new snow.

mod common;

use snowscape_skiers::{SkiArea, SkiError, SkiParams, SkiScratch, Terminus, TrackTexture, step};

#[test]
fn line_coverage_is_the_box_filtered_width() {
    // 10 m cells, 10 texels per cell: 1 m texels.
    let mut tex = TrackTexture::new(4, 4, 10.0, 10.0, 10).unwrap();
    // A horizontal line through texel centres (y = 5.5) of width 1 m: one full row.
    tex.draw_segment((2.0, 5.5), (30.0, 5.5), 1.0);
    for u in 5..25 {
        assert!(
            (tex.get(u, 5) - 1.0).abs() < 1e-6,
            "u {u}: {}",
            tex.get(u, 5)
        );
        assert_eq!(tex.get(u, 4), 0.0);
        assert_eq!(tex.get(u, 6), 0.0);
    }
    // Halfway between rows, width 1 m: two rows at one half each.
    tex.draw_segment((2.0, 20.0), (30.0, 20.0), 1.0);
    assert!((tex.get(10, 19) - 0.5).abs() < 1e-6 && (tex.get(10, 20) - 0.5).abs() < 1e-6);
    // Any offset and width: the column sum is the width in texels (exact 1-D box filter).
    for (y, w) in [(30.3, 0.4), (31.77, 2.3), (34.1, 1.6)] {
        let mut t = TrackTexture::new(4, 4, 10.0, 10.0, 10).unwrap();
        t.draw_segment((0.0, y), (40.0, y), w);
        let sum: f32 = (0..40).map(|v| t.get(17, v)).sum();
        assert!((f64::from(sum) - w).abs() < 1e-5, "y {y} w {w}: {sum}");
    }
    // Only the touched tiles exist.
    assert_eq!(tex.allocated_tiles(), 1);
    let mut big = TrackTexture::new(100, 100, 10.0, 10.0, 8).unwrap();
    big.draw_segment((5.0, 5.0), (15.0, 12.0), 1.0);
    assert_eq!(big.allocated_tiles(), 1);
    assert_eq!(big.size(), (800, 800));
}

#[test]
fn tracks_fade_under_added_snow() {
    let mut tex = TrackTexture::new(6, 6, 10.0, 10.0, 4).unwrap();
    tex.draw_segment((0.0, 31.25), (60.0, 31.25), 2.5);
    let before: Vec<f32> = (0..24).map(|u| tex.get(u, 12)).collect();
    assert!(before.iter().all(|&v| v > 0.99));
    // Nothing added: unchanged.
    tex.fade(&[0.0; 36], 0.1).unwrap();
    assert_eq!((0..24).map(|u| tex.get(u, 12)).collect::<Vec<_>>(), before);
    // 10 cm on the western three columns (all rows), 30 cm on column 5, none on columns 3..5:
    // fully inside column 1 the factor is exp(-1); at column 5's centre exp(-3); texels of
    // column 3 that lie between centres 3 and 4 keep their value (both neighbours 0).
    let mut added = vec![0.0f32; 36];
    for r in 0..6 {
        for c in 0..3 {
            added[r * 6 + c] = 0.1;
        }
        added[r * 6 + 5] = 0.3;
    }
    tex.fade(&added, 0.1).unwrap();
    let e1 = (-1.0f32).exp();
    for u in 0..10 {
        // Texel centres up to cell 2's centre (texel 10 is at 2.625 cells - beyond).
        assert!(
            (tex.get(u, 12) - e1).abs() < 1e-5,
            "u {u}: {}",
            tex.get(u, 12)
        );
    }
    assert!((tex.get(14, 12) - 1.0).abs() < 1e-6, "{}", tex.get(14, 12));
    assert!(
        (tex.get(22, 12) - (-3.0f32).exp()).abs() < 1e-5,
        "{}",
        tex.get(22, 12)
    );
    assert!(tex.get(11, 12) > e1 && tex.get(11, 12) < 1.0);
    // Negative (removed snow) counts as nothing.
    let snap: Vec<f32> = (0..24).map(|u| tex.get(u, 12)).collect();
    tex.fade(&[-1.0; 36], 0.1).unwrap();
    assert_eq!((0..24).map(|u| tex.get(u, 12)).collect::<Vec<_>>(), snap);
}

#[test]
fn fading_checks_its_input() {
    let mut tex = TrackTexture::new(3, 3, 10.0, 10.0, 4).unwrap();
    let e = tex.fade(&[0.0; 8], 0.1).unwrap_err();
    assert!(
        matches!(
            e,
            SkiError::LengthMismatch {
                got: 8,
                expected: 9,
                ..
            }
        ),
        "{e}"
    );
    let mut bad = [0.0f32; 9];
    bad[4] = f32::NAN;
    let e = tex.fade(&bad, 0.1).unwrap_err();
    assert!(matches!(e, SkiError::BadValue { index: 4, .. }), "{e}");
    let e = tex.fade(&[0.0; 9], 0.0).unwrap_err();
    assert!(
        matches!(
            e,
            SkiError::InvalidParameter {
                name: "fade_depth_m",
                ..
            }
        ),
        "{e}"
    );
    let e = TrackTexture::new(3, 3, 10.0, 10.0, 0).unwrap_err();
    assert!(
        matches!(
            e,
            SkiError::InvalidParameter {
                name: "texels_per_cell",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn skiing_draws_and_snowfall_fades_the_area_texture() {
    let params = SkiParams::default();
    let mut t = common::plane(16, 40, 10.0, 32.0);
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 2).unwrap();
    area.spawn_weighted(&params, &t, 5).unwrap();
    let mut scratch = SkiScratch::default();
    while !area.skiers().is_empty() {
        step(&params, &mut area, &mut t, &mut scratch, 2.0).unwrap();
    }
    let drawn = area.texture().total();
    // About track length × width / texel area of full-intensity texels.
    let length: f64 = area.finished_tracks().iter().map(|tr| tr.length_m).sum();
    let (tx, ty) = area.texture().texel_size();
    let expect = length * params.track_width_m / (tx * ty);
    assert!(
        drawn > 0.6 * expect && drawn < 1.05 * expect,
        "{drawn} vs {expect}"
    );
    // 20 cm of snow everywhere: e^-2 of every texel.
    area.fade_tracks(&params, &vec![0.2; 16 * 40]).unwrap();
    let faded = area.texture().total();
    assert!(
        (faded / drawn - (-2.0f64).exp()).abs() < 1e-4,
        "{}",
        faded / drawn
    );
}

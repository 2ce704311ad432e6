//! The nodata outline is an edge of the terrain with the grid border's condition (issue 46,
//! item 9): with the open border, snow that flows into nodata leaves the terrain as
//! `border_outflow`, as across the grid's border, and does not pile against it; with the
//! closed border nodata cells are walls.

use snowscape_avalanche::{AvalancheParams, AvalancheScratch, AvalancheState, Border, step};
use snowscape_terrain::{GridGeometry, NodataMask};

/// Columns of the slope's valid part; the grid is wider by `NODATA_COLUMNS`.
const VALID_COLUMNS: usize = 45;
const NODATA_COLUMNS: usize = 7;
const ROWS: usize = 40;
const DX: f64 = 2.0;

/// A 35° plane descending east, `w` columns, with the columns from [`VALID_COLUMNS`] on nodata
/// when `w` is wider, and a block of snow 1.5 m thick uphill.
fn slope(w: usize) -> AvalancheState {
    let g = GridGeometry::new(w, ROWS, DX, DX).unwrap();
    let tan = 35f64.to_radians().tan();
    // (Nodata cells hold a value no valid cell has: the flow must not read it.)
    let bed: Vec<f64> = (0..w * ROWS)
        .map(|i| {
            let c = i % w;
            if c < VALID_COLUMNS {
                500.0 - tan * DX * c as f64
            } else {
                -9999.0
            }
        })
        .collect();
    let mask = NodataMask::from_invalid((0..w * ROWS).map(|i| i % w >= VALID_COLUMNS).collect());
    let mut s = AvalancheState::new(&g, &mask, &bed).unwrap();
    let depth: Vec<f64> = (0..w * ROWS)
        .map(|i| {
            let (c, r) = (i % w, i / w);
            if (8..18).contains(&c) && (12..28).contains(&r) {
                1.5
            } else {
                0.0
            }
        })
        .collect();
    s.set_thickness(&depth).unwrap();
    s
}

/// Runs `s` for `steps` steps of 0.5 s; returns the outflow, and checks the volume budget
/// closes and nodata holds no snow at every step. The paper's law, which the bounds were
/// measured with (under the default samosAT law the rims differ by 1-2 %: its friction reads
/// the cells' velocities, and a nodata cell's averages its pipes with those beyond it).
fn run(s: &mut AvalancheState, border: Border, steps: usize) -> f64 {
    let params = AvalancheParams {
        border,
        ..AvalancheParams::paper()
    };
    let v0 = s.flowing_volume();
    let mut scratch = AvalancheScratch::default();
    let mut outflow = 0.0;
    let w = s.geometry().width();
    for _ in 0..steps {
        outflow += step(&params, s, &mut scratch, 0.5).unwrap().border_outflow;
        let v = s.flowing_volume();
        assert!(
            ((v + outflow - v0) / v0).abs() < 1e-12,
            "{border:?}: {v0} m³ -> {v} m³ + {outflow} m³ out"
        );
        for r in 0..ROWS {
            for c in VALID_COLUMNS..w {
                assert_eq!(
                    s.thickness_at(c, r),
                    0.0,
                    "{border:?}: snow on nodata ({c}, {r})"
                );
            }
        }
    }
    outflow
}

/// Mean flowing thickness of the last valid column, m.
fn rim(s: &AvalancheState) -> f64 {
    (0..ROWS)
        .map(|r| s.thickness_at(VALID_COLUMNS - 1, r))
        .sum::<f64>()
        / ROWS as f64
}

#[test]
fn snow_flowing_into_nodata_leaves_as_across_the_grid_border() {
    let mut outlined = slope(VALID_COLUMNS + NODATA_COLUMNS);
    let mut cropped = slope(VALID_COLUMNS);
    let v0 = cropped.flowing_volume();
    assert_eq!(outlined.flowing_volume(), v0);
    // 10 s: the front has crossed the outline (the border), half the snow is gone.
    let out_nodata = run(&mut outlined, Border::Open, 20);
    let out_border = run(&mut cropped, Border::Open, 20);
    assert!(out_border > 0.3 * v0, "{out_border} of {v0} m³");
    // The same outflow and the same rim to ~1e-5 (measured; not to the bit: a nodata cell's
    // velocity averages its pipes with those of the cells beyond it, which the ghost ring has
    // not).
    assert!(
        (out_nodata - out_border).abs() < 1e-3 * v0,
        "into nodata {out_nodata} m³, across the border {out_border} m³"
    );
    let (a, b) = (rim(&outlined), rim(&cropped));
    assert!(b > 0.1, "the border column holds {b} m");
    assert!((a - b).abs() <= 0.01 * b, "rim {a} m, border column {b} m");
    // In the end all of it slides off.
    let out = out_nodata + run(&mut outlined, Border::Open, 60);
    assert!((out - v0).abs() < 1e-6 * v0, "{out} of {v0} m³");
}

#[test]
fn a_closed_border_makes_nodata_a_wall() {
    let mut s = slope(VALID_COLUMNS + NODATA_COLUMNS);
    let out = run(&mut s, Border::Closed, 80);
    assert_eq!(out, 0.0);
    // The snow piles against the outline.
    assert!(rim(&s) > 0.5, "rim {} m", rim(&s));
}

//! The distance-to-terminus map: values, monotonicity, automaton equivalence, dead-ends.

mod common;

use snowscape_skiers::{SkiError, SkiParams, Terminus, TerminusMap};
use snowscape_terrain::SnowLayer;

#[test]
fn plane_distance_is_the_distance_to_the_bottom_row() {
    // 20° plane descending south, 10 m cells: the bottom row is the valley floor.
    let t = common::plane(12, 30, 10.0, 20.0);
    let floor = f64::from(t.bedrock[29 * 12]) + 1.5 + 1e-3;
    let map =
        TerminusMap::compute(&SkiParams::default(), &t, &Terminus::BelowAltitude(floor)).unwrap();
    for row in 0..30 {
        for col in 0..12 {
            let d = map.distance_at(row * 12 + col);
            let expect = (29 - row) as f32 * 10.0;
            assert!((d - expect).abs() < 1e-3, "({col},{row}): {d} vs {expect}");
        }
    }
    assert!(map.sweeps() >= 2);
}

#[test]
fn distance_decreases_towards_the_terminus_along_the_fall_line() {
    let t = common::varied_mountain(64, 10.0);
    let params = SkiParams::default();
    let map = TerminusMap::compute(&params, &t, &Terminus::LocalMinima).unwrap();
    let d = map.distance();
    let surface = t.surface();
    // Every cell with a route has a neighbour, not higher, whose distance is smaller by the
    // step length: following it walks down to a terminus.
    let mut checked = 0;
    for row in 0..64 {
        for col in 0..64 {
            let i = row * 64 + col;
            if d[i] == 0.0 || !d[i].is_finite() {
                continue;
            }
            let mut best = f32::INFINITY;
            for dr in -1isize..=1 {
                for dc in -1isize..=1 {
                    let (c, r) = (col as isize + dc, row as isize + dr);
                    if (dc, dr) == (0, 0) || !(0..64).contains(&c) || !(0..64).contains(&r) {
                        continue;
                    }
                    let j = r as usize * 64 + c as usize;
                    if surface[j] <= surface[i] {
                        let l = 10.0 * ((dc * dc + dr * dr) as f32).sqrt();
                        best = best.min(d[j] + l);
                    }
                }
            }
            assert_eq!(best, d[i], "cell ({col},{row}) is not at the fixed point");
            checked += 1;
        }
    }
    assert!(checked > 3000, "{checked}");
    // The summit is far from the edge, the edge is a terminus.
    assert!(d[32 * 64 + 32] > 250.0, "{}", d[32 * 64 + 32]);
    assert_eq!(d[0], 0.0);
    // Along a radius from the summit outwards the distance falls monotonically.
    for col in 33..63 {
        assert!(d[32 * 64 + col] < d[32 * 64 + col - 1], "col {col}");
    }
}

#[test]
fn swept_automaton_equals_synchronous_automaton() {
    let params = SkiParams::default();
    let mut t = common::varied_mountain(40, 10.0);
    // A snow-free gash makes dead-ends and detours.
    for r in 5..30 {
        t.layer_mut(SnowLayer::Stable)[r * 40 + 25] = 0.0;
        t.layer_mut(SnowLayer::Unstable)[r * 40 + 25] = 0.0;
    }
    let low = t.surface().iter().fold(f32::INFINITY, |a, &b| a.min(b));
    for rule in [
        Terminus::LocalMinima,
        Terminus::BelowAltitude(f64::from(low) + 20.0),
        Terminus::Cells(vec![39 * 40 + 3]),
    ] {
        let a = TerminusMap::compute(&params, &t, &rule).unwrap();
        let b = TerminusMap::compute_synchronous(&params, &t, &rule).unwrap();
        assert_eq!(a.distance(), b.distance(), "{rule:?}");
        assert!(b.sweeps() > a.sweeps(), "{} vs {}", b.sweeps(), a.sweeps());
    }
}

#[test]
fn snow_free_cells_and_basins_without_route_are_dead_ends() {
    let params = SkiParams::default();
    let mut t = common::plane(10, 20, 10.0, 25.0);
    // Rows 8..=9 lose their snow: the slope above can no longer reach the bottom.
    for i in 80..100 {
        t.layer_mut(SnowLayer::Stable)[i] = 0.0;
        t.layer_mut(SnowLayer::Unstable)[i] = 0.0;
    }
    let map = TerminusMap::compute(&params, &t, &Terminus::Cells((190..200).collect())).unwrap();
    for i in 0..100 {
        assert!(map.distance_at(i).is_infinite(), "cell {i}");
    }
    for i in 100..200 {
        assert!(map.distance_at(i).is_finite(), "cell {i}");
    }
    // Spawning draws only cells with a route.
    for k in 0..200 {
        let cell = map.spawn_cell(k as f64 / 200.0).unwrap();
        assert!((100..190).contains(&cell), "{cell}");
    }
}

#[test]
fn spawn_weights_favour_cells_far_from_the_terminus() {
    let t = common::plane(10, 40, 10.0, 25.0);
    let map = TerminusMap::compute(
        &SkiParams::default(),
        &t,
        &Terminus::Cells((390..400).collect()),
    )
    .unwrap();
    let draws = 4000;
    let (mut top, mut bottom) = (0, 0);
    for k in 0..draws {
        let cell = map.spawn_cell((k as f64 + 0.5) / draws as f64).unwrap();
        if cell / 10 < 10 {
            top += 1;
        } else if cell / 10 >= 30 {
            bottom += 1;
        }
    }
    // Weights ∝ distance: rows 0..10 weigh (39..30), rows 30..39 weigh (9..1): ratio ≈ 7.7.
    let ratio = top as f64 / bottom as f64;
    assert!((6.5..9.0).contains(&ratio), "top {top} bottom {bottom}");
}

#[test]
fn bad_termini_are_typed_errors() {
    let params = SkiParams::default();
    let t = common::plane(8, 8, 10.0, 20.0);
    let e = TerminusMap::compute(&params, &t, &Terminus::Cells(vec![64])).unwrap_err();
    assert!(
        matches!(
            e,
            SkiError::CellOutOfRange {
                index: 64,
                cells: 64,
                ..
            }
        ),
        "{e}"
    );
    let e = TerminusMap::compute(&params, &t, &Terminus::Point { x: -5.0, y: 10.0 }).unwrap_err();
    assert!(
        matches!(e, SkiError::OutsideGrid { x, .. } if x == -5.0),
        "{e}"
    );
    let e = TerminusMap::compute(&params, &t, &Terminus::BelowAltitude(0.0)).unwrap_err();
    assert!(matches!(e, SkiError::NoTerminus(_)), "{e}");
    let e = TerminusMap::compute(&params, &t, &Terminus::BelowAltitude(f64::NAN)).unwrap_err();
    assert!(matches!(e, SkiError::InvalidParameter { .. }), "{e}");
    // A point inside works and gives distance 0 there.
    let map = TerminusMap::compute(&params, &t, &Terminus::Point { x: 45.0, y: 5.0 }).unwrap();
    assert_eq!(map.distance_at(7 * 8 + 4), 0.0);
}

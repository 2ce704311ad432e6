//! The sine-wave refinement: the paper's frequency formula and its effective slope.

use snowscape_skiers::refine::SineTrack;
use snowscape_skiers::{effective_slope, turn_frequency};

fn deg(d: f64) -> f64 {
    d.to_radians()
}

#[test]
fn frequency_matches_hand_computed_values() {
    // s = 45°, st = 30°, a = 5 m: sqrt(0.5 − 0.25) / (4·5·0.5) = 0.5 / 10 = 0.05 /m.
    assert!((turn_frequency(deg(45.0), deg(30.0), 5.0) - 0.05).abs() < 1e-12);
    // s = 60°: sqrt(0.75 − 0.25) / 10 = 0.0707107 /m.
    assert!((turn_frequency(deg(60.0), deg(30.0), 5.0) - 0.5f64.sqrt() / 10.0).abs() < 1e-12);
    // s = 90°, st = 30°, a = 2 m: sqrt(1 − 0.25) / (4·2·0.5) = 0.8660254 / 4.
    assert!((turn_frequency(deg(90.0), deg(30.0), 2.0) - 0.75f64.sqrt() / 4.0).abs() < 1e-12);
    // s = 40°, st = 20°, a = 5 m: sin²40 = 0.4131759, sin²20 = 0.1169778,
    // sqrt(0.2961981) = 0.5442409, 4·5·0.3420201 = 6.840403 → 0.0795627 /m.
    assert!((turn_frequency(deg(40.0), deg(20.0), 5.0) - 0.0795627).abs() < 1e-6);
    // At or below the target slope no turn is needed; no amplitude cannot slow down.
    assert_eq!(turn_frequency(deg(30.0), deg(30.0), 5.0), 0.0);
    assert_eq!(turn_frequency(deg(10.0), deg(30.0), 5.0), 0.0);
    assert_eq!(turn_frequency(deg(50.0), deg(30.0), 0.0), 0.0);
}

#[test]
fn effective_slope_of_the_chosen_frequency_is_the_target() {
    for s in [31.0, 35.0, 45.0, 60.0, 75.0, 89.0] {
        for st in [15.0, 25.0, 30.0] {
            for a in [1.0, 5.0, 12.0] {
                let f = turn_frequency(deg(s), deg(st), a);
                let se = effective_slope(deg(s), f, a);
                assert!(
                    (se - deg(st)).abs() < 1e-9,
                    "s {s} st {st} a {a}: {}",
                    se.to_degrees()
                );
            }
        }
    }
    // No turns: the effective slope is the slope; more turns make it gentler.
    assert_eq!(effective_slope(deg(40.0), 0.0, 5.0), deg(40.0));
    assert!(effective_slope(deg(40.0), 0.1, 5.0) < effective_slope(deg(40.0), 0.05, 5.0));
}

#[test]
fn sine_track_is_continuous_across_frequency_changes() {
    let mut s = SineTrack {
        amplitude_m: 5.0,
        frequency: 0.05,
        phase: 0.0,
    };
    // A quarter wavelength (5 m at 0.05 /m) reaches the amplitude.
    let mut o = 0.0;
    for _ in 0..50 {
        o = s.advance(0.1);
    }
    assert!((o - 5.0).abs() < 1e-9, "{o}");
    // Changing the frequency does not jump the offset.
    let before = s.offset();
    s.frequency = 0.2;
    let after = s.advance(1e-6);
    assert!((after - before).abs() < 1e-4);
    // The offset is across the heading: heading east (1, 0) offsets along y.
    let (x, y) = s.point(10.0, 20.0, 1.0, 0.0);
    assert_eq!(x, 10.0);
    assert!((y - (20.0 - s.offset())).abs() < 1e-12);
}

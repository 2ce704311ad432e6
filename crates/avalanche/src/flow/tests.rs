//! Unit tests of the flow: the lane widths against the one-cell kernels.
use super::*;

/// The four- and eight-lane kernels give the bits of the one-lane (scalar) ones: random bed and
/// depths, nodata cells, both borders, dry, wet and mixed snow, square and oblong cells.
#[test]
fn lanes_match_scalar() {
    let hash = |i: usize, seed: u64| {
        let mut x = (i as u64 ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .wrapping_add(0x632B_E59B_D9B4_E019);
        x ^= x >> 30;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 27;
        x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
        x ^= x >> 31;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let cases = [
        (70, 50, 2.0, 2.0, Border::Open, 1.0),
        (61, 43, 3.0, 2.0, Border::Closed, 0.4),
        (40, 64, 5.0, 5.0, Border::Open, 0.0),
    ];
    for (case, &(w, h, dx, dy, border, alpha)) in cases.iter().enumerate() {
        let seed = case as u64 + 11;
        let g = GridGeometry::new(w, h, dx, dy).unwrap();
        let bed: Vec<f64> = (0..w * h)
            .map(|i| 4.0 * hash(i, seed) + 0.9 * (i / w) as f64 + 0.2 * (i % w) as f64)
            .collect();
        let mask = NodataMask::from_invalid((0..w * h).map(|i| hash(i, seed ^ 7) < 0.02).collect());
        let mut s = AvalancheState::new(&g, &mask, &bed).unwrap();
        let depth: Vec<f64> = (0..w * h)
            .map(|i| {
                let v = hash(i, seed ^ 3);
                if v < 0.4 { 0.0 } else { 2.0 * v }
            })
            .collect();
        s.set_thickness(&depth).unwrap();
        // The shallow form, and the projected one on the first two cases; each friction
        // law, Voellmy also with per-cell μ and ξ.
        for (law, maps) in [
            (FrictionLaw::Coulomb, false),
            (FrictionLaw::Voellmy, false),
            (FrictionLaw::Voellmy, true),
            (FrictionLaw::SamosAt, false),
        ] {
            let params = AvalancheParams {
                border,
                alpha,
                k_viscous: 0.02,
                friction: law,
                slope_gravity: if case < 2 {
                    SlopeGravity::Projected
                } else {
                    SlopeGravity::Shallow
                },
                ..AvalancheParams::default()
            };
            let mut s = s.clone();
            if maps {
                let mu = (0..w * h).map(|i| 0.1 + 0.3 * hash(i, seed ^ 5)).collect();
                let xi = (0..w * h)
                    .map(|i| 200.0 + 4000.0 * hash(i, seed ^ 9))
                    .collect();
                s.set_friction_maps(&FrictionMaps::new(&g, Some(mu), Some(xi)).unwrap())
                    .unwrap();
            }
            let run = |lanes: usize| {
                let mut st = s.clone();
                let mut scratch = AvalancheScratch::default();
                scratch.set_max_lanes(lanes);
                let reports: Vec<AvalancheReport> = (0..12)
                    .map(|_| step(&params, &mut st, &mut scratch, 0.3).unwrap())
                    .collect();
                (st, reports)
            };
            let (a, ra) = run(1);
            assert!(ra.iter().map(|r| r.substeps).sum::<usize>() > 20);
            // Four lanes (AVX) and eight (AVX-512), where the CPU has them.
            for lanes in [4, 8] {
                let (b, rb) = run(lanes);
                assert_eq!(a, b, "case {case} {law:?} maps {maps} lanes {lanes}");
                assert_eq!(ra, rb, "case {case} {law:?} maps {maps} lanes {lanes}");
            }
        }
    }
}

/// The nearest-valid fill: a nodata cell takes the bed of its first valid edge neighbour in
/// row-major order, else of a corner neighbour, else of the nearest valid cell; a grid with no
/// nodata (or no valid cell) has no map.
#[test]
fn nodata_cells_take_the_nearest_valid_cell() {
    // 5 x 4, `#` nodata:
    //   . . # # #
    //   . # # # #
    //   . . # # #
    //   # # # # #
    let (w, h) = (5, 4);
    let rows = ["..###", ".####", "..###", "#####"];
    let invalid: Vec<bool> = rows
        .iter()
        .flat_map(|r| r.chars().map(|ch| ch == '#'))
        .collect();
    let src = state::nearest_valid(w, h, &NodataMask::from_invalid(invalid.clone()));
    let at = |c: usize, r: usize| src[r * w + c] as usize;
    for i in (0..w * h).filter(|&i| !invalid[i]) {
        assert_eq!(src[i] as usize, i);
    }
    // (1, 1): edge neighbours (1, 0), (0, 1), (1, 2) valid: the first in row-major order.
    assert_eq!(at(1, 1), 1);
    // (2, 0): edge neighbour (1, 0). (2, 1): no valid edge neighbour, corners (1, 0) first.
    assert_eq!(at(2, 0), 1);
    assert_eq!(at(2, 1), 1);
    // (0, 3): edge neighbour (0, 2); (2, 3): corner (1, 2); (3, 1): two steps, through (2, 1).
    assert_eq!(at(0, 3), 2 * w);
    assert_eq!(at(2, 3), 2 * w + 1);
    assert_eq!(at(3, 1), 1);
    assert!(state::nearest_valid(w, h, &NodataMask::all_valid()).is_empty());
    assert!(state::nearest_valid(w, h, &NodataMask::from_invalid(vec![true; w * h])).is_empty());

    // The flow state reads those beds; the ghost ring that of the nearest grid cell's source.
    let bed: Vec<f64> = (0..w * h).map(|i| i as f64 + 100.0).collect();
    let g = GridGeometry::new(w, h, 1.0, 1.0).unwrap();
    let s = AvalancheState::new(&g, &NodataMask::from_invalid(invalid), &bed).unwrap();
    assert_eq!(s.bed_at(1, 1), 101.0);
    assert_eq!(s.bed_at(2, 3), 111.0);
    assert_eq!(s.bed[s.pad(2, 3) + s.pw], 111.0, "ghost below (2, 3)");
}

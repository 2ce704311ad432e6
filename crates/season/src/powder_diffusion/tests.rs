use super::*;
use snowscape_terrain::{Grid, GridGeometry, NodataMask};

fn terrain(geo: GridGeometry, bed: impl FnMut(usize, usize) -> f32) -> LayeredTerrain {
    LayeredTerrain::from_bedrock(Grid::from_fn(geo, bed))
}

fn powder(t: &LayeredTerrain) -> &[f32] {
    t.layer(SnowLayer::Powder)
}

/// Every face's slope excess over the rest slope, m/m (interior faces between valid cells).
fn excesses(t: &LayeredTerrain, rest: f64) -> Vec<f64> {
    let g = t.geometry();
    let a = t.surface();
    let mut out = Vec::new();
    for r in 0..g.height() {
        for c in 0..g.width() {
            let i = g.index(c, r);
            for (j, len) in [
                (g.neighbour(c, r, 1, 0), g.cell_size_x()),
                (g.neighbour(c, r, 0, 1), g.cell_size_y()),
            ] {
                if let Some(j) = j.filter(|&j| t.mask().is_valid(i) && t.mask().is_valid(j)) {
                    let s = (a[i] as f64 - a[j] as f64).abs() / len;
                    out.push((s - rest).max(0.0));
                }
            }
        }
    }
    out
}

/// A cone of powder on flat bedrock at sea level (so f32 surfaces resolve small slopes), slope 2 (well above rest), 1 m cells.
fn cone(n: usize) -> LayeredTerrain {
    let mut t = terrain(GridGeometry::square(n, n, 1.0).unwrap(), |_, _| 0.0);
    let m = n as f32 / 2.0;
    for r in 0..n {
        for c in 0..n {
            let d = ((c as f32 + 0.5 - m).powi(2) + (r as f32 + 0.5 - m).powi(2)).sqrt();
            t.layer_mut(SnowLayer::Powder)[r * n + c] = (2.0 * (m * 0.6 - d)).max(0.0);
        }
    }
    t
}

#[test]
fn closed_box_conserves_volume() {
    let geo = GridGeometry::new(23, 17, 2.0, 3.0).unwrap();
    let mut t = terrain(geo.clone(), |c, r| {
        (snowscape_terrain::random::uniform(7, 0, (r * 23 + c) as u64) * 6.0) as f32
    });
    for i in 0..geo.len() {
        t.layer_mut(SnowLayer::Powder)[i] =
            (snowscape_terrain::random::uniform(7, 1, i as u64) * 2.0) as f32;
    }
    let p = DiffusionParams {
        border: DiffusionBorder::Closed,
        ..Default::default()
    };
    let before = t.snow_volume();
    let mut scratch = DiffusionScratch::default();
    let mut moved = 0.0;
    for _ in 0..50 {
        let r = step(&p, &mut t, &mut scratch, 0.5).unwrap();
        assert_eq!(r.border_outflow, 0.0);
        moved += r.moved;
        t.check_invariants().unwrap();
    }
    let after = t.snow_volume();
    assert!(moved > 0.1 * before, "moved {moved}");
    assert!(
        (after - before).abs() < 1e-6 * before,
        "{before} -> {after}"
    );
}

#[test]
fn open_border_outflow_closes_the_budget() {
    // Bedrock falls eastwards at slope 1 (above rest): powder drains off the east edge.
    let geo = GridGeometry::square(12, 6, 1.0).unwrap();
    let mut t = terrain(geo, |c, _| 50.0 - c as f32);
    t.layer_mut(SnowLayer::Powder).fill(0.3);
    let p = DiffusionParams::default();
    let mut scratch = DiffusionScratch::default();
    let mut out = 0.0;
    let before = t.snow_volume();
    for _ in 0..40 {
        let r = step(&p, &mut t, &mut scratch, 0.5).unwrap();
        assert!(r.border_outflow >= 0.0);
        out += r.volume_change().removed;
    }
    let after = t.snow_volume();
    assert!(out > 0.1 * before, "outflow {out}");
    assert!(
        (before - after - out).abs() < 1e-5 * before,
        "{before} {after} {out}"
    );
    t.check_invariants().unwrap();
}

#[test]
fn a_powder_pile_relaxes_to_the_rest_slope_with_decreasing_excess() {
    let p = DiffusionParams {
        border: DiffusionBorder::Closed,
        ..Default::default()
    };
    let mut t = cone(24);
    let mut scratch = DiffusionScratch::default();
    let total = |t: &LayeredTerrain| excesses(t, 0.5).iter().sum::<f64>();
    let mut last = total(&t);
    assert!(last > 10.0);
    for k in 0..1000 {
        step(&p, &mut t, &mut scratch, 0.5).unwrap();
        let now = total(&t);
        assert!(
            now <= last * (1.0 + 1e-6) + 1e-6,
            "step {k}: {now} > {last}"
        );
        last = now;
    }
    // Near rest the flux is linear in the excess, so the approach is geometric, not finite.
    let max_slope = excesses(&t, 0.0).into_iter().fold(0.0f64, f64::max);
    assert!(max_slope < 0.5 * 1.01 && max_slope > 0.45, "{max_slope}");
    t.check_invariants().unwrap();
}

#[test]
fn small_modes_decay_like_the_discrete_heat_equation() {
    // Rest slope 0: linear diffusion of A with λ = k_m δt / 2 per step. A Neumann cosine mode
    // of wavenumber m decays by 1 − λ (2 − 2 cos(π m / N)) per step, exactly.
    let n = 16;
    let geo = GridGeometry::new(n, 3, 2.0, 5.0).unwrap();
    let mut t = terrain(geo, |_, _| 10.0);
    let m = 6.0f64;
    let mode = |c: usize| (std::f64::consts::PI * m * (c as f64 + 0.5) / n as f64).cos();
    for r in 0..3 {
        for c in 0..n {
            t.layer_mut(SnowLayer::Powder)[r * n + c] = (5.0 + 0.1 * mode(c)) as f32;
        }
    }
    let p = DiffusionParams {
        rest_slope: 0.0,
        k_m: 0.4,
        border: DiffusionBorder::Closed,
    };
    let (dt, steps) = (0.5, 20);
    let lambda = p.k_m * dt / 2.0;
    let g = 1.0 - lambda * (2.0 - 2.0 * (std::f64::consts::PI * m / n as f64).cos());
    let mut scratch = DiffusionScratch::default();
    for _ in 0..steps {
        assert_eq!(step(&p, &mut t, &mut scratch, dt).unwrap().substeps, 1);
    }
    let amp = 0.1 * g.powi(steps);
    for r in 0..3 {
        for c in 0..n {
            let got = powder(&t)[r * n + c] as f64 - 5.0;
            let want = amp * mode(c);
            assert!((got - want).abs() < 2e-5, "({c},{r}) {got} vs {want}");
        }
    }
    assert!(g.powi(steps) < 0.5, "the test must see real decay");
}

#[test]
fn steep_thin_powder_never_goes_negative_and_nodata_is_a_wall() {
    // A cliff: thin powder on a 45° bedrock staircase, a nodata cell inside, long steps.
    let geo = GridGeometry::square(10, 10, 1.0).unwrap();
    let mut invalid = vec![false; geo.len()];
    invalid[geo.index(5, 5)] = true;
    let bed = Grid::new(
        geo.clone(),
        (0..geo.len())
            .map(|i| 3.0 * (i % 10) as f32 + ((i * 13) % 7) as f32)
            .collect(),
        NodataMask::from_invalid(invalid),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    for i in 0..geo.len() {
        if i != geo.index(5, 5) {
            t.layer_mut(SnowLayer::Powder)[i] = 0.05 * (i % 3) as f32;
        }
    }
    let p = DiffusionParams {
        k_m: 5.0,
        ..Default::default()
    };
    assert_eq!(p.substeps(2.0), 40);
    let mut scratch = DiffusionScratch::default();
    let mut removed = 0.0;
    let before = t.snow_volume();
    for _ in 0..5 {
        let r = step(&p, &mut t, &mut scratch, 2.0).unwrap();
        removed += r.border_outflow;
        t.check_invariants().unwrap();
        assert_eq!(powder(&t)[geo.index(5, 5)], 0.0);
    }
    assert!((before - removed - t.snow_volume()).abs() < 1e-5 * before.max(1.0));
}

#[test]
fn rest_slope_is_measured_per_direction_on_rectangular_cells() {
    // 0.4 m steps in both directions: slope 0.4 along x (1 m cells) is at rest,
    // 0.8 along y (0.5 m cells) is not.
    let geo = GridGeometry::new(6, 6, 1.0, 0.5).unwrap();
    let mut t = terrain(geo, |c, r| 0.4 * (c + r) as f32);
    t.layer_mut(SnowLayer::Powder).fill(1.0);
    let p = DiffusionParams {
        border: DiffusionBorder::Closed,
        ..Default::default()
    };
    let before = t.layer(SnowLayer::Powder).to_vec();
    step(&p, &mut t, &mut DiffusionScratch::default(), 0.5).unwrap();
    let after = powder(&t);
    // Row 0 (north) is lowest: it gains powder from the south; the last row loses.
    assert!(after[2] > before[2] && after[32] < before[32]);
    // Nothing moves along x: the west and east ends of interior rows (where an x flux would
    // not balance) keep theirs.
    for c in 0..6 {
        assert!((after[18 + c] - 1.0).abs() < 1e-6, "{}", after[18 + c]);
    }
}

#[test]
fn zero_time_step_and_bad_parameters() {
    let mut t = cone(8);
    let before = t.clone();
    let r = step(
        &DiffusionParams::default(),
        &mut t,
        &mut DiffusionScratch::default(),
        0.0,
    )
    .unwrap();
    assert_eq!(r, DiffusionReport::default());
    assert_eq!(t, before);
    let bad = DiffusionParams {
        rest_slope: -0.1,
        ..Default::default()
    };
    assert!(step(&bad, &mut t, &mut DiffusionScratch::default(), 1.0).is_err());
    let parsed: DiffusionParams = serde_json::from_str(r#"{"border": "closed"}"#).unwrap();
    assert_eq!(parsed.border, DiffusionBorder::Closed);
}

/// The season keeps its avalanche hazard map through powder diffusion steps (it reads only
/// unstable snow): diffusion must leave every layer but the powder untouched, to the bit.
#[test]
fn diffusion_moves_powder_only() {
    let geo = GridGeometry::new(19, 13, 2.0, 3.0).unwrap();
    let mut t = terrain(geo.clone(), |c, r| {
        (snowscape_terrain::random::uniform(8, 0, (r * 19 + c) as u64) * 9.0) as f32
    });
    for layer in [
        SnowLayer::Compacted,
        SnowLayer::Stable,
        SnowLayer::Unstable,
        SnowLayer::Powder,
    ] {
        for i in 0..geo.len() {
            t.layer_mut(layer)[i] =
                (snowscape_terrain::random::uniform(8, 1 + layer.index() as u64, i as u64)) as f32;
        }
    }
    let before = t.snow.clone();
    let mut scratch = DiffusionScratch::default();
    let mut moved = 0.0;
    for _ in 0..10 {
        moved += step(&DiffusionParams::default(), &mut t, &mut scratch, 0.5)
            .unwrap()
            .moved;
    }
    assert!(moved > 0.0);
    for layer in [SnowLayer::Compacted, SnowLayer::Stable, SnowLayer::Unstable] {
        assert_eq!(t.layer(layer), &before[layer.index()][..], "{layer:?}");
    }
}

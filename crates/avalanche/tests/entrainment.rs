//! Entrainment of the snowpack (`snowscape_avalanche::entrainment`): an avalanche running
//! down a snow-covered slope scours its track, grows, and lays down more than it released;
//! the volumes close; stable snow erodes only to its depth, compacted snow never; a larger
//! erosion energy entrains less; turned off, the track keeps every bit of its snow.

use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheWorkspace, EntrainmentParams, ReleasedCells,
    RestOutcome, RunOptions,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

const W: usize = 60;
const H: usize = 160;
const CELL: f64 = 5.0;

/// A 35° slope facing south (rows grow downhill) for 110 rows, then level ground; 0.4 m of
/// powder, 0.2 m of unstable, 0.6 m of stable and 0.5 m of compacted snow everywhere.
fn snowy_slope() -> LayeredTerrain {
    let g = GridGeometry::square(W, H, CELL).unwrap();
    let tan = 35f64.to_radians().tan();
    let bed: Vec<f32> = (0..W * H)
        .map(|i| {
            let r = (i / W) as f64;
            (1000.0 + tan * CELL * (110.0 - r.min(110.0))) as f32
        })
        .collect();
    let grid = Grid::new(g, bed, NodataMask::all_valid()).unwrap();
    let mut t = LayeredTerrain::from_bedrock(grid);
    for (layer, d) in [
        (SnowLayer::Powder, 0.4),
        (SnowLayer::Unstable, 0.2),
        (SnowLayer::Stable, 0.6),
        (SnowLayer::Compacted, 0.5),
    ] {
        t.layer_mut(layer).fill(d);
    }
    t
}

/// A 12 x 8-cell slab at the top of the slope, centred across it.
fn release() -> Vec<usize> {
    (4..12)
        .flat_map(|r| (W / 2 - 6..W / 2 + 6).map(move |c| r * W + c))
        .collect()
}

fn try_run(
    t: &mut LayeredTerrain,
    entrainment: EntrainmentParams,
) -> Result<RestOutcome, AvalancheError> {
    // The paper's law, which the bounds below were measured with (the season's default law
    // entrains too: crates/season's tests).
    let flow = AvalancheParams {
        entrainment,
        ..AvalancheParams::paper()
    };
    AvalancheWorkspace::new().run_to_rest::<AvalancheError>(
        t,
        ReleasedCells::new(&release(), None),
        &flow,
        &RunOptions::default(),
        SnowLayer::Stable,
        |_| Ok(()),
    )
}

fn run(t: &mut LayeredTerrain, entrainment: EntrainmentParams) -> RestOutcome {
    try_run(t, entrainment).unwrap()
}

#[test]
fn an_avalanche_scours_its_track_and_grows() {
    let mut t = snowy_slope();
    let before: f64 = t.total_depth().iter().map(|&d| f64::from(d)).sum();
    let out = run(&mut t, EntrainmentParams::default());
    let s = &out.summary;
    // The flow took snow from its track: more than it released, and lays it all down.
    assert!(
        out.entrained_m3 > 2.0 * out.released_m3,
        "entrained {} m³, released {} m³",
        out.entrained_m3,
        out.released_m3
    );
    assert!((s.entrained_volume_m3 - out.entrained_m3).abs() < 1e-9);
    let closure = (out.released_m3 + out.entrained_m3 - out.deposited_m3 - s.border_outflow_m3)
        .abs()
        / (out.released_m3 + out.entrained_m3);
    assert!(closure < 1e-6, "closure {closure}");
    assert!(s.volume_closure_rel < 1e-6, "{}", s.volume_closure_rel);
    // The terrain keeps its volume (nothing left the grid on this slope).
    assert_eq!(s.border_outflow_m3, 0.0);
    let after: f64 = t.total_depth().iter().map(|&d| f64::from(d)).sum();
    assert!(
        ((after - before) / before).abs() < 1e-5,
        "{before} -> {after} m³"
    );
    // The track below the release (the centre column, rows 20-100) lost a good part of its
    // powder (the flow widens over the uniform cover and scours all of its width).
    let powder = t.layer(SnowLayer::Powder);
    let track: Vec<f32> = (20..100).map(|r| powder[r * W + W / 2]).collect();
    let mean = track.iter().sum::<f32>() / track.len() as f32;
    assert!(mean < 0.3, "powder left in the track: {mean} m of 0.4");
    // The entrained map lists the scoured cells, the track among them.
    let scour = RestOutcome::dense(&out.entrained, W * H);
    assert!(scour[60 * W + W / 2] > 0.1, "{}", scour[60 * W + W / 2]);
    // Stable snow erodes to at most its entrainable depth; compacted snow never.
    let (st, co) = (t.layer(SnowLayer::Stable), t.layer(SnowLayer::Compacted));
    let deposit = RestOutcome::dense(&out.deposited, W * H);
    for i in 0..W * H {
        assert_eq!(co[i], 0.5, "compacted snow eroded at {i}");
        let stable_left = st[i] as f64 - deposit[i];
        assert!(
            stable_left >= 0.6 - 0.3 - 1e-5,
            "cell {i}: {stable_left} m of stable snow left of 0.6"
        );
    }
    // Beside the flow the snowpack is untouched.
    assert_eq!(powder[50 * W + 2], 0.4);
}

#[test]
fn without_entrainment_the_track_keeps_its_snow() {
    let mut t = snowy_slope();
    let out = run(
        &mut t,
        EntrainmentParams {
            enabled: false,
            ..EntrainmentParams::default()
        },
    );
    assert_eq!(out.entrained_m3, 0.0);
    assert!(out.entrained.is_empty());
    let released: std::collections::HashSet<usize> = release().into_iter().collect();
    let powder = t.layer(SnowLayer::Powder);
    for (i, &p) in powder.iter().enumerate() {
        if !released.contains(&i) {
            assert_eq!(p, 0.4, "powder moved at {i} with entrainment off");
        }
    }
    assert!((out.deposited_m3 - out.released_m3).abs() / out.released_m3 < 1e-6);
}

#[test]
fn a_larger_erosion_energy_entrains_less() {
    let volumes: Vec<f64> = [2000.0, 5000.0, 20000.0]
        .iter()
        .map(|&e| {
            run(
                &mut snowy_slope(),
                EntrainmentParams {
                    erosion_energy_j_kg: e,
                    ..EntrainmentParams::default()
                },
            )
            .entrained_m3
        })
        .collect();
    assert!(
        volumes[0] > volumes[1] && volumes[1] > volumes[2] && volumes[2] > 0.0,
        "{volumes:?}"
    );
}

#[test]
fn bad_entrainment_parameters_are_refused_before_anything_moves() {
    let mut t = snowy_slope();
    let before = t.layer(SnowLayer::Powder).to_vec();
    let err = try_run(
        &mut t,
        EntrainmentParams {
            erosion_energy_j_kg: f64::NAN,
            ..EntrainmentParams::default()
        },
    )
    .unwrap_err();
    assert!(
        err.to_string().contains("entrainment.erosion_energy_j_kg"),
        "{err}"
    );
    assert_eq!(t.layer(SnowLayer::Powder), &before[..]);
}

use super::*;
use snowscape_terrain::random::uniform;
use snowscape_terrain::{Grid, NodataMask, surface};

fn terrain_from(geo: GridGeometry, f: impl FnMut(usize, usize) -> f32) -> LayeredTerrain {
    LayeredTerrain::from_bedrock(Grid::from_fn(geo, f))
}

fn run(t: &mut LayeredTerrain, p: &SheddingParams) -> SheddingReport {
    let r = step(p, t, &mut SheddingScratch::default(), 1.0).unwrap();
    t.check_invariants().unwrap();
    r
}

/// A wall rising westwards at `angle`° from column `foot` to column 0, flat east of it.
fn wall(angle: f64, foot: usize) -> LayeredTerrain {
    let geo = GridGeometry::square(40, 12, 5.0).unwrap();
    let t = angle.to_radians().tan() as f32 * 5.0;
    terrain_from(geo, move |c, _| 100.0 + t * foot.saturating_sub(c) as f32)
}

#[test]
fn holding_depths_follow_the_cited_laws() {
    let p = SheddingParams::default();
    assert!((p.holding_depth(30.0) - 145.0 * (-4.2f64).exp()).abs() < 1e-9);
    assert!((p.holding_depth(30.0) - 2.17).abs() < 0.01);
    assert!((p.holding_depth(45.0) - 0.266).abs() < 0.001);
    assert_eq!(p.holding_depth(60.0), 0.05);
    assert_eq!(p.holding_depth(89.0), 0.05);
    let pl = SheddingParams {
        law: HoldingLaw::PowerLaw,
        ..Default::default()
    };
    assert!((pl.holding_depth(60.0) - 0.890).abs() < 0.001);
    assert_eq!(pl.holding_depth(2.0), pl.holding_depth(10.0));
    // Monotone: steeper holds less.
    for s in 0..89 {
        assert!(p.holding_depth(s as f64 + 1.0) <= p.holding_depth(s as f64));
    }
}

#[test]
fn flat_ground_is_untouched() {
    let geo = GridGeometry::square(16, 16, 5.0).unwrap();
    let mut t = terrain_from(geo, |_, _| 1500.0);
    t.layer_mut(SnowLayer::Powder).fill(3.0);
    let before = t.clone();
    let r = run(&mut t, &SheddingParams::default());
    assert_eq!(r, SheddingReport::default());
    assert_eq!(t, before);
}

#[test]
fn a_snow_laden_70_degree_wall_dumps_its_snow_onto_the_flat_foot() {
    let mut t = wall(70.0, 20);
    t.layer_mut(SnowLayer::Powder).fill(0.6);
    t.layer_mut(SnowLayer::Stable).fill(0.4);
    let before = t.snow_volume();
    let r = run(&mut t, &SheddingParams::default());
    let w = 40;
    let depth = |c: usize, row: usize| t.depth_at(row * w + c);
    // The wall keeps its 5 cm, but for its lowest cells, which the debris cone at its foot
    // partly buries (their snow surface is less steep).
    for row in 0..12 {
        for c in 0..18 {
            assert!(
                (depth(c, row) - 0.05).abs() < 1e-5,
                "({c},{row}) {}",
                depth(c, row)
            );
        }
        for c in 18..20 {
            assert!(depth(c, row) < 0.2, "({c},{row}) {}", depth(c, row));
        }
    }
    // Everything else landed on the flat ground at the foot of the wall, within a few cells.
    let gain = |cols: std::ops::Range<usize>| -> f64 {
        (0..12)
            .flat_map(|row| cols.clone().map(move |c| (c, row)))
            .map(|(c, row)| depth(c, row) as f64 - 1.0)
            .sum::<f64>()
            * 25.0
    };
    let shed_wall = 12.0 * 20.0 * 0.95 * 25.0;
    let foot = gain(20..40);
    let near = gain(20..27);
    eprintln!("{r:?}; foot gained {foot:.1} m³ ({near:.1} within 30 m) of {shed_wall} m³");
    // Only the wall cells of the first and last rows lose a share past the borders (the
    // surface continued diagonally descends there).
    assert!(r.border_outflow_m3 < 0.1 * shed_wall, "{r:?}");
    assert!((foot - (shed_wall - r.border_outflow_m3)).abs() < 1e-3 * shed_wall);
    let profile: Vec<String> = (18..30).map(|c| format!("{:.2}", depth(c, 5))).collect();
    eprintln!("row 5 from col 18: {}", profile.join(" "));
    assert!(near > 0.9 * foot, "{near} of {foot}");
    assert!((before - r.border_outflow_m3 - t.snow_volume()).abs() < 1e-6 * before);
    assert!((r.moved_m3 - r.received_m3 - r.border_outflow_m3).abs() < 1e-6 * r.moved_m3);
    assert!(r.moved_m3 >= shed_wall * 0.999, "{r:?}");
    assert_eq!(r.unsettled_cells, 0);
    // Deposits land as unstable snow; the wall lost its powder first, then stable snow.
    let unstable = t.layer(SnowLayer::Unstable);
    let deepest = (20..40).map(|c| unstable[5 * w + c]).fold(0.0, f32::max);
    assert!(deepest > 1.0, "{deepest}");
    assert_eq!(t.layer(SnowLayer::Powder)[5 * w + 10], 0.0);
    assert!((t.layer(SnowLayer::Stable)[5 * w + 10] - 0.05).abs() < 1e-6);
}

#[test]
fn cells_steeper_than_60_degrees_keep_at_most_their_holding_depth() {
    // A rough cone: slopes from 0 to ~75°.
    let geo = GridGeometry::square(48, 48, 4.0).unwrap();
    let mut t = terrain_from(geo, |c, r| {
        let d = ((c as f32 - 24.0).hypot(r as f32 - 24.0)) * 4.0;
        let n = (uniform(9, 0, (r * 48 + c) as u64) as f32) * 0.8;
        400.0 - 0.02 * d * d + n
    });
    for (i, p) in t.layer_mut(SnowLayer::Powder).iter_mut().enumerate() {
        *p = 0.5 + uniform(9, 1, i as u64) as f32;
    }
    t.layer_mut(SnowLayer::Compacted).fill(0.1);
    // Every cell from 30° sheds (FSM2oshd's threshold; the season's default starts at 60°).
    let p = SheddingParams {
        min_slope_deg: 30.0,
        ..SheddingParams::default()
    };
    let before = t.snow_volume();
    let r = run(&mut t, &p);
    let slopes = surface::slopes(
        &t.bedrock
            .iter()
            .zip(t.layer(SnowLayer::Compacted))
            .map(|(b, c)| b + c)
            .collect::<Vec<_>>(),
        t.geometry(),
        t.mask(),
    );
    // Every cell steeper than 60° keeps its holding depth (5 cm); one that received debris
    // late judges its slope on the surfaces of the moment (module documentation) and may keep
    // a few millimetres more.
    let (mut steep, mut worst, mut sum) = (0, 0.0f32, 0.0f64);
    for (i, s) in slopes.iter().enumerate() {
        let deg = s.to_degrees() as f64;
        if deg > 60.0 {
            steep += 1;
            let over = t.depth_at(i) - p.holding_depth(deg) as f32;
            worst = worst.max(over);
            sum += t.depth_at(i) as f64;
        }
    }
    eprintln!(
        "{steep} cells above 60°: mean depth {:.4} m, worst excess {worst:.4} m",
        sum / steep as f64
    );
    assert!(
        worst < 0.005,
        "a cell above 60° keeps {worst} m over its holding depth"
    );
    assert!(sum / (steep as f64) < 0.051, "{}", sum / steep as f64);
    assert!(steep > 50, "only {steep} cells above 60°");
    assert!(
        r.border_outflow_m3 > 0.0,
        "the cone sheds off its foot: {r:?}"
    );
    let after = t.snow_volume();
    assert!((before - r.border_outflow_m3 - after).abs() < 1e-6 * before);
    assert!((r.moved_m3 - r.received_m3 - r.border_outflow_m3).abs() < 1e-6 * r.moved_m3);
}

#[test]
fn random_terrain_with_nodata_conserves_snow_and_a_second_step_moves_much_less() {
    let geo = GridGeometry::new(37, 29, 3.0, 4.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n).map(|i| uniform(4, 9, i as u64) < 0.07).collect();
    let bed = Grid::new(
        geo.clone(),
        (0..n)
            .map(|i| {
                let (c, r) = geo.col_row(i);
                (50.0 * ((c as f64 * 0.4).sin() + (r as f64 * 0.3).cos())
                    + 3.0 * uniform(4, 0, i as u64)) as f32
            })
            .collect(),
        NodataMask::from_invalid(invalid.clone()),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    // No compacted snow: shedding it would change the bed, and so the slopes of the next step.
    for i in (0..n).filter(|&i| !invalid[i]) {
        for (k, layer) in SnowLayer::ALL.into_iter().enumerate().skip(1) {
            t.layer_mut(layer)[i] = (uniform(4, 1 + k as u64, i as u64) * 0.6) as f32;
        }
    }
    let before = t.snow_volume();
    let p = SheddingParams::default();
    let mut scratch = SheddingScratch::default();
    let r = step(&p, &mut t, &mut scratch, 0.5).unwrap();
    t.check_invariants().unwrap();
    assert!(r.moved_m3 > 0.05 * before, "{r:?}");
    assert!((r.moved_m3 - r.received_m3 - r.border_outflow_m3).abs() < 1e-6 * r.moved_m3);
    let after = t.snow_volume();
    assert!(
        (before - r.border_outflow_m3 - after).abs() < 1e-6 * before,
        "{before} - {} != {after}",
        r.border_outflow_m3
    );
    assert!(t.snow.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    assert_eq!(r.unsettled_cells, 0);
    // Near rest: a second step (through the cached order) only sheds what slopes that
    // steepened behind the sweep release (module documentation).
    let again = step(&p, &mut t, &mut scratch, 0.5).unwrap();
    eprintln!("{r:?}, then {again:?}");
    assert!(again.moved_m3 <= 0.15 * r.moved_m3, "{again:?} after {r:?}");
}

#[test]
fn a_drift_on_lower_bedrock_still_reaches_rest() {
    // Bedrock descends east; column 6 is a hollow filled by a deep drift, so its snow surface
    // stands above the bare bedrock of column 5: snow shed from the wall west of it meets a
    // snow surface that does not follow the bedrock, and must still reach rest.
    let geo = GridGeometry::square(14, 3, 5.0).unwrap();
    let mut t = terrain_from(geo, |c, _| match c {
        0..=4 => 100.0 + 8.0 * (5 - c) as f32,
        _ => 100.0 - 0.5 * (c - 5) as f32,
    });
    for r in 0..3 {
        t.layer_mut(SnowLayer::Stable)[r * 14 + 6] = 3.0;
    }
    t.layer_mut(SnowLayer::Powder).fill(1.0);
    let p = SheddingParams {
        min_slope_deg: 0.0,
        dynamic_ratio: 0.05,
        ..Default::default()
    };
    let mut scratch = SheddingScratch::default();
    let r = step(&p, &mut t, &mut scratch, 1.0).unwrap();
    t.check_invariants().unwrap();
    let again = step(&p, &mut t, &mut scratch, 1.0).unwrap();
    assert!(again.moved_m3 <= 0.05 * r.moved_m3, "{again:?} after {r:?}");
}

#[test]
fn same_bytes_on_one_and_two_threads() {
    let geo = GridGeometry::square(64, 50, 5.0).unwrap();
    let make = || {
        let mut t = terrain_from(geo.clone(), |c, r| {
            (300.0
                + 60.0 * ((c as f64) * 0.2).sin() * ((r as f64) * 0.15).cos()
                + 30.0 * uniform(5, 0, (r * 64 + c) as u64)) as f32
        });
        t.layer_mut(SnowLayer::Powder).fill(1.2);
        t
    };
    let go = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut t = make();
                let r = run(&mut t, &SheddingParams::default());
                (t, r)
            })
    };
    let (a, ra) = go(1);
    let (b, rb) = go(2);
    assert!(ra.cells_shed > 100, "{ra:?}");
    assert_eq!(ra, rb);
    for k in 0..4 {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.snow[k]), bits(&b.snow[k]), "layer {k}");
    }
}

#[test]
fn a_reused_scratch_gives_the_same_result() {
    let mut t = wall(70.0, 20);
    t.layer_mut(SnowLayer::Powder).fill(1.0);
    let p = SheddingParams::default();
    let mut scratch = SheddingScratch::default();
    let mut fresh = t.clone();
    step(&p, &mut t, &mut scratch, 1.0).unwrap();
    // A different terrain through the same scratch.
    let mut other = wall(65.0, 10);
    other.layer_mut(SnowLayer::Powder).fill(1.0);
    let mut other_fresh = other.clone();
    step(&p, &mut other, &mut scratch, 1.0).unwrap();
    step(&p, &mut other_fresh, &mut SheddingScratch::default(), 1.0).unwrap();
    assert_eq!(other, other_fresh);
    step(&p, &mut fresh, &mut SheddingScratch::default(), 1.0).unwrap();
    assert_eq!(t, fresh);
    // Other parameters through the same scratch (its holding table is rebuilt), and a second
    // step on the snow the first left (its surfaces are set up afresh).
    let q = SheddingParams {
        exp_rate_per_deg: 0.15,
        min_slope_deg: 40.0,
        ..p.clone()
    };
    let mut again = t.clone();
    again
        .layer_mut(SnowLayer::Powder)
        .iter_mut()
        .for_each(|v| *v += 0.3);
    let mut again_fresh = again.clone();
    let before = again.clone();
    step(&q, &mut again, &mut scratch, 1.0).unwrap();
    step(&q, &mut again_fresh, &mut SheddingScratch::default(), 1.0).unwrap();
    assert_eq!(again, again_fresh);
    assert_ne!(again, before, "the second step moved nothing");
}

#[test]
fn bad_parameters_are_typed_errors_and_round_trip() {
    let mut t = wall(70.0, 20);
    let bad = SheddingParams {
        dynamic_ratio: 0.0,
        ..Default::default()
    };
    let e = step(&bad, &mut t, &mut SheddingScratch::default(), 1.0).unwrap_err();
    assert!(e.to_string().contains("dynamic_ratio = 0"), "{e}");
    for bad in [
        SheddingParams {
            min_slope_deg: 95.0,
            ..Default::default()
        },
        SheddingParams {
            flow_exponent: f64::NAN,
            ..Default::default()
        },
        SheddingParams {
            min_holding_depth_m: -1.0,
            ..Default::default()
        },
        SheddingParams {
            entrain_min_slope_deg: -5.0,
            ..Default::default()
        },
        SheddingParams {
            interval_days: f64::NAN,
            ..Default::default()
        },
        SheddingParams {
            interval_days: 1e9,
            ..Default::default()
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
    assert!(
        step(
            &SheddingParams::default(),
            &mut t,
            &mut SheddingScratch::default(),
            -1.0
        )
        .is_err()
    );
    let p = SheddingParams::default();
    let json = serde_json::to_string(&p).unwrap();
    assert_eq!(serde_json::from_str::<SheddingParams>(&json).unwrap(), p);
    let partial: SheddingParams =
        serde_json::from_str(r#"{"law": "power_law", "deposit_layer": "stable"}"#).unwrap();
    assert_eq!(partial.law, HoldingLaw::PowerLaw);
    assert_eq!(partial.deposit_layer, SnowLayer::Stable);
    assert!(serde_json::from_str::<SheddingParams>(r#"{"min_slope": 3}"#).is_err());
}

#[test]
fn extreme_roughness_still_conserves_snow() {
    // 15 m of noise on 3 m cells: pits and spikes everywhere, the worst case for the cascade.
    let geo = GridGeometry::square(40, 40, 3.0).unwrap();
    let mut t = terrain_from(geo, |c, r| {
        (15.0 * uniform(6, 0, (r * 40 + c) as u64) + 0.5 * c as f64) as f32
    });
    t.layer_mut(SnowLayer::Powder).fill(2.0);
    let before = t.snow_volume();
    let r = run(&mut t, &SheddingParams::default());
    eprintln!("{r:?}");
    assert!(r.moved_m3 > 0.0);
    assert!((before - r.border_outflow_m3 - t.snow_volume()).abs() < 1e-6 * before);
    assert!((r.moved_m3 - r.received_m3 - r.border_outflow_m3).abs() < 1e-6 * r.moved_m3);
}

#[test]
fn the_holding_table_follows_both_laws_within_1e_5() {
    for law in [HoldingLaw::Exponential, HoldingLaw::PowerLaw] {
        let p = SheddingParams {
            law,
            dynamic_ratio: 0.3,
            ..SheddingParams::default()
        };
        let table = HoldingTable::new(&p);
        for k in 0..=9000 {
            let deg = k as f64 * 0.01;
            let tan = deg.to_radians().tan() as f32;
            let exact = p.holding_depth(deg);
            let got = f64::from(table.hold(tan, false));
            assert!(
                (got - exact).abs() <= 1e-5 * exact,
                "{law:?} {deg}°: {got} vs {exact}"
            );
            let dynamic = (exact * 0.3).max(p.min_holding_depth_m);
            let got = f64::from(table.hold(tan, true));
            assert!(
                (got - dynamic).abs() <= 1e-5 * dynamic,
                "{law:?} {deg}° received"
            );
        }
        assert_eq!(
            table.hold(f32::INFINITY, false),
            p.holding_depth(90.0) as f32
        );
        assert_eq!(table.hold(f32::NAN, false), table.hold(0.0, false));
    }
}

#[test]
fn the_retained_depth_tables_find_the_root_within_a_tenth_of_a_millimetre() {
    // Between the table's points and past its end (cliff drops), for both laws, with and
    // without the dynamic ratio, on 1 m, 10 m and 100 m cells: the tabulated depth a receiving
    // cell keeps against the root of `d = H((c + d) λ)` by bisection on the same holding depths.
    for law in [HoldingLaw::Exponential, HoldingLaw::PowerLaw] {
        for dynamic_ratio in [1.0, 0.3] {
            let p = SheddingParams {
                law,
                dynamic_ratio,
                ..SheddingParams::default()
            };
            let holding = HoldingTable::new(&p);
            for l in [1.0f32, 10.0, 14.142_136, 100.0] {
                let table = RetainedTable::new(&holding, 1.0 / l);
                let hold = |s: f64| f64::from(holding.hold(s as f32, true));
                let mut worst = 0.0f64;
                for k in 0..20_000 {
                    let c = -200.0 + 1200.0 * uniform(7, 3, k) * uniform(7, 4, k);
                    let (mut lo, mut hi) = (0.0f64, 200.0f64);
                    for _ in 0..80 {
                        let mid = 0.5 * (lo + hi);
                        if mid - hold((c + mid) / f64::from(l)) > 0.0 {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    let got = f64::from(table.keep(&holding, c as f32));
                    worst = worst.max((got - lo).abs());
                }
                assert!(
                    worst <= 1e-4,
                    "{law:?} ratio {dynamic_ratio} {l} m: {worst} m"
                );
            }
        }
    }
}

#[test]
fn the_slope_bound_passes_over_no_cell_that_sheds() {
    // Rough terrain with compacted snow of every depth and a ragged nodata outline: the cells
    // the bound lets through must be exactly those a full evaluation of every cell finds.
    let geo = GridGeometry::new(61, 47, 2.0, 3.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n).map(|i| uniform(8, 9, i as u64) < 0.05).collect();
    let bed = Grid::new(
        geo.clone(),
        (0..n)
            .map(|i| {
                let (c, r) = geo.col_row(i);
                (2500.0
                    + 30.0 * ((c as f64 * 0.5).sin() * (r as f64 * 0.4).cos())
                    + 6.0 * uniform(8, 0, i as u64)) as f32
            })
            .collect(),
        NodataMask::from_invalid(invalid.clone()),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    for i in (0..n).filter(|&i| !invalid[i]) {
        for (k, layer) in SnowLayer::ALL.into_iter().enumerate() {
            t.layer_mut(layer)[i] = (uniform(8, 1 + k as u64, i as u64) * 1.5) as f32;
        }
    }
    for min_slope_deg in [30.0, 50.0, 60.0, 75.0] {
        let p = SheddingParams {
            min_slope_deg,
            ..SheddingParams::default()
        };
        let holding = HoldingTable::new(&p);
        let mut scratch = SheddingScratch::default();
        scratch.refresh_strips(&t).unwrap();
        let tan_min = min_slope_deg.to_radians().tan() as f32;
        let found = with_validity!(t.mask(), |valid| over_holding_depth(
            &p, &holding, &t, &scratch, &geo, valid, tan_min
        ));
        // Every cell, no bound.
        let nb = neighbours(&geo);
        let bed: Vec<f32> = (0..n).map(|i| t.bedrock[i] + t.snow[0][i]).collect();
        let surf = t.surface();
        let mut all = Vec::new();
        with_validity!(t.mask(), |valid| {
            for i in (0..n).filter(|&i| valid.at(i)) {
                let b = |j: usize| bed[j];
                let on_bed = steepest_descent(bed[i], b, b, &geo, valid, &nb, i);
                let on_snow = steepest_descent(surf[i], |j| surf[j], b, &geo, valid, &nb, i);
                let tan = on_bed.min(on_snow);
                let depth = t.depth_at(i);
                let excess = depth - holding.hold(tan, false);
                if tan >= tan_min && excess > MIN_SHED_M {
                    all.push((i as u32, tan, excess));
                }
            }
        });
        assert!(!all.is_empty(), "{min_slope_deg}°");
        assert_eq!(found, all, "{min_slope_deg}°");
    }
}

/// A 70° face (columns 0-9) above a 40° slope (10-29) above flat ground: the face carries 0.5 m
/// of fresh powder, the 40° slope 1 m of its own settled snow (its holding depth is 0.54 m,
/// but at 40° < `min_slope_deg` it does not shed it).
fn face_over_a_40_degree_slope() -> LayeredTerrain {
    let geo = GridGeometry::square(60, 8, 5.0).unwrap();
    let (t70, t40) = (
        70f32.to_radians().tan() * 5.0,
        40f32.to_radians().tan() * 5.0,
    );
    let mut t = terrain_from(geo, move |c, _| {
        let below_face = (10usize.saturating_sub(c)) as f32 * t70;
        100.0 + below_face + 30usize.saturating_sub(c.max(10)) as f32 * t40
    });
    for row in 0..8 {
        for c in 0..60 {
            let i = row * 60 + c;
            if c < 10 {
                t.layer_mut(SnowLayer::Powder)[i] = 0.5;
            } else if c < 30 {
                t.layer_mut(SnowLayer::Stable)[i] = 1.0;
            }
        }
    }
    t
}

#[test]
fn a_sluff_runs_over_a_40_degree_slope_without_stripping_its_own_snow() {
    let mut t = face_over_a_40_degree_slope();
    let before = t.snow_volume();
    let r = run(&mut t, &SheddingParams::default());
    assert!(r.cells_shed > 0 && r.border_outflow_m3 == 0.0, "{r:?}");
    assert!((t.snow_volume() - before).abs() <= 1e-5 * before);
    let stable = t.layer(SnowLayer::Stable);
    for row in 0..8 {
        for c in 11..29 {
            // Its own snow stays where it was (the sluff passes over it as unstable debris), to
            // the f32 round-off of a snow surface at 100-200 m.
            let d = stable[row * 60 + c];
            assert!((d - 1.0).abs() < 1e-4, "({c},{row}) {d}");
        }
    }
    // FSM2oshd's rule (every receiver sheds its excess): the sluff strips the slope's cover
    // to about its holding depth and piles it on the flat below.
    let mut t = face_over_a_40_degree_slope();
    let fsm = SheddingParams {
        entrain_min_slope_deg: 0.0,
        ..Default::default()
    };
    run(&mut t, &fsm);
    let mean_40: f64 = (0..8)
        .flat_map(|row| (12..28).map(move |c| row * 60 + c))
        .map(|i| t.depth_at(i) as f64)
        .sum::<f64>()
        / (8.0 * 16.0);
    assert!(
        mean_40 < 0.8,
        "mean depth on the 40° slope {mean_40} (1 m before)"
    );
    assert!((t.snow_volume() - before).abs() <= 1e-5 * before);
}

/// A 60×64 grid whose face (70°) runs down from the first 40 cells of its slope direction onto
/// flat ground: southwards (crossing the boundary between the two strips of rows at row 32) or
/// eastwards (every flow within its strip). Returns the mean depth at each position along the
/// slope, and the report.
fn face_profile(southwards: bool) -> (Vec<f64>, SheddingReport) {
    let (w, h) = if southwards { (60, 64) } else { (64, 60) };
    let geo = GridGeometry::square(w, h, 5.0).unwrap();
    let rise = 70f64.to_radians().tan() as f32 * 5.0;
    let mut t = terrain_from(geo, move |c, r| {
        let along = if southwards { r } else { c };
        100.0 + rise * 40usize.saturating_sub(along) as f32
    });
    t.layer_mut(SnowLayer::Powder).fill(0.6);
    t.layer_mut(SnowLayer::Stable).fill(0.4);
    let before = t.snow_volume();
    let report = run(&mut t, &SheddingParams::default());
    let after = t.snow_volume() + report.border_outflow_m3;
    assert!(
        (after - before).abs() <= 1e-5 * before,
        "{before} -> {after}"
    );
    let depth = t.total_depth();
    let profile = (0..64)
        .map(|along| {
            let across = if southwards { w } else { h };
            (0..across)
                .map(|k| {
                    let (c, r) = if southwards { (k, along) } else { (along, k) };
                    f64::from(depth[r * w + c])
                })
                .sum::<f64>()
                / across as f64
        })
        .collect();
    (profile, report)
}

#[test]
fn a_face_across_the_strip_boundary_sheds_as_one_within_a_strip() {
    assert_eq!(strip_rows(64), vec![0..32, 32..64]);
    let (across, r_across) = face_profile(true);
    let (within, r_within) = face_profile(false);
    assert_eq!(r_across.unsettled_cells, 0, "{r_across:?}");
    assert_eq!(r_within.unsettled_cells, 0, "{r_within:?}");
    // The face keeps the floor of the holding depth, across the boundary (rows 31 and 32)
    // too; its snow lies at the foot.
    for (along, depth) in across.iter().enumerate().take(39).skip(1) {
        assert!(*depth <= 0.06, "row {along}: {depth}");
    }
    let volume = |p: &[f64]| p[39..].iter().sum::<f64>();
    let centre = |p: &[f64]| {
        p.iter()
            .enumerate()
            .skip(39)
            .map(|(k, d)| k as f64 * d)
            .sum::<f64>()
            / volume(p)
    };
    eprintln!(
        "debris {} m and centre {} across, {} m and {} within",
        volume(&across),
        centre(&across),
        volume(&within),
        centre(&within)
    );
    assert!(volume(&across) > 40.0 * 0.9, "{across:?}");
    // The debris cone runs out as far (within half a cell: 0.23 cell apart; one sweep of the whole grid,
    // its order breaking ties by index, puts them 0.12 cell apart).
    assert!(
        (centre(&across) - centre(&within)).abs() <= 0.5,
        "{across:?} {within:?}"
    );
    assert!(
        (r_across.moved_m3 - r_within.moved_m3).abs() <= 0.05 * r_within.moved_m3,
        "{r_across:?} {r_within:?}"
    );
}

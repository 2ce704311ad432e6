//! Skiers as agents: downhill, on snow, tracking the target slope, stopping.

mod common;

use snowscape_skiers::{
    SkiArea, SkiParams, SkiScratch, StopReason, Terminus, step, turn_frequency,
};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Steps until every skier stopped (at most `max_steps` steps of `dt` s).
fn run_out(
    params: &SkiParams,
    area: &mut SkiArea,
    t: &mut LayeredTerrain,
    dt: f64,
    max_steps: usize,
) {
    let mut scratch = SkiScratch::default();
    for _ in 0..max_steps {
        if area.skiers().is_empty() {
            return;
        }
        step(params, area, t, &mut scratch, dt).unwrap();
    }
    panic!(
        "{} skiers still skiing after {max_steps} steps",
        area.skiers().len()
    );
}

/// The varied mountain with a snow-free band (rock rib) east of the summit and scattered
/// snow-free cells.
fn patchy_mountain() -> LayeredTerrain {
    let mut t = common::varied_mountain(80, 10.0);
    for i in 0..80 * 80 {
        let (c, r) = (i % 80, i / 80);
        let rib = (44..47).contains(&c) && (20..60).contains(&r);
        let hole = (c * 7 + r * 13) % 37 == 0;
        if rib || hole {
            for l in [SnowLayer::Stable, SnowLayer::Unstable] {
                t.layer_mut(l)[i] = 0.1;
            }
        }
    }
    t
}

#[test]
fn skiers_go_downhill_and_stay_on_snow() {
    let params = SkiParams::default();
    let mut t = patchy_mountain();
    let depth0 = t.total_depth();
    let surface0 = t.surface();
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 11).unwrap();
    let ids = area.spawn_weighted(&params, &t, 60).unwrap();
    assert_eq!(ids.len(), 60);
    run_out(&params, &mut area, &mut t, 0.5, 20_000);
    let tracks = area.finished_tracks();
    assert_eq!(tracks.len(), 60);
    let map = area.terminus();
    let mut at_terminus = 0;
    for tr in tracks {
        for &c in &tr.cells {
            assert!(
                depth0[c] > params.min_snow_depth_m as f32 || map.is_terminus(c),
                "skier {} entered cell {c} with {} m of snow",
                tr.id,
                depth0[c]
            );
        }
        let (first, last) = (tr.cells[0], *tr.cells.last().unwrap());
        let drop = surface0[first] - surface0[last];
        assert!(drop > 0.0, "skier {} ended {drop} m below its start", tr.id);
        if tr.stop == Some(StopReason::Terminus) {
            at_terminus += 1;
            assert!(map.is_terminus(last));
        }
        // Overall downhill: the distance to the terminus fell along the coarse path.
        assert!(map.distance_at(last) < map.distance_at(first));
    }
    assert!(
        at_terminus >= 50,
        "only {at_terminus} of 60 reached a terminus"
    );
}

#[test]
fn chosen_slopes_track_the_target_slope() {
    let params = SkiParams::default();
    let mut t = common::varied_mountain(80, 10.0);
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 5).unwrap();
    area.spawn_weighted(&params, &t, 80).unwrap();
    // And 40 more on the steep upper slopes (ring of radius 60 m around the summit).
    for k in 0..40 {
        let a = k as f64 * std::f64::consts::TAU / 40.0;
        area.spawn_at(&params, &t, 400.0 + 60.0 * a.cos(), 400.0 + 60.0 * a.sin())
            .unwrap();
    }
    run_out(&params, &mut area, &mut t, 0.5, 20_000);
    let view_slope = |i: usize| -> f64 {
        // Fall-line slope of the bedrock cone at cell i (snow is uniform).
        let (c, r) = ((i % 80) as f64 + 0.5 - 40.0, (i / 80) as f64 + 0.5 - 40.0);
        let rr = c.hypot(r) * 10.0;
        55.0 - 45.0 * (rr / 400.0).min(1.0)
    };
    let st = params.target_slope_deg;
    let (mut steep_n, mut steep_err, mut steep_fall) = (0usize, 0.0f64, 0.0f64);
    let (mut gentle_n, mut gentle_gap) = (0usize, 0.0f64);
    for tr in area.finished_tracks() {
        for ch in &tr.choices {
            let fall = view_slope(ch.cell);
            let s = f64::from(ch.slope_rad).to_degrees();
            if fall > st + 10.0 {
                steep_n += 1;
                steep_err += (s - st).abs();
                steep_fall += fall - st;
                // Frequencies follow the paper's formula for the chosen slope.
                let f = turn_frequency(f64::from(ch.slope_rad), st.to_radians(), 5.0).max(0.01);
                assert!((f64::from(ch.frequency) - f).abs() < 1e-6);
            } else if fall < st - 10.0 {
                gentle_n += 1;
                gentle_gap += fall - s;
            }
        }
    }
    assert!(steep_n > 150 && gentle_n > 150, "{steep_n} {gentle_n}");
    let steep_err = steep_err / steep_n as f64;
    let steep_fall = steep_fall / steep_n as f64;
    let gentle_gap = gentle_gap / gentle_n as f64;
    eprintln!(
        "steep: mean |s - st| {steep_err:.1}° vs fall line {steep_fall:.1}°; gentle: fall - chosen {gentle_gap:.1}°"
    );
    // On steep ground skiers traverse: their slopes stay near st, far closer than the fall line.
    assert!(steep_err < 6.5, "{steep_err}");
    assert!(steep_err < 0.5 * steep_fall, "{steep_err} vs {steep_fall}");
    // On gentle ground nothing reaches st: they take nearly the fall line.
    assert!(gentle_gap < 6.0, "{gentle_gap}");
}

#[test]
fn skiers_stop_when_stuck_or_too_far_and_are_removed() {
    let params = SkiParams::default();
    // Snow only on a 4x4 island in the middle of a 30° slope; the terminus (bottom row) cannot
    // be reached from it.
    let mut t = common::plane(20, 30, 10.0, 30.0);
    for i in 0..600 {
        let (c, r) = (i % 20, i / 20);
        if !((8..12).contains(&c) && (10..14).contains(&r)) {
            t.layer_mut(SnowLayer::Stable)[i] = 0.0;
            t.layer_mut(SnowLayer::Unstable)[i] = 0.0;
        }
    }
    let mut area = SkiArea::new(&params, &t, Terminus::Cells((580..600).collect()), 4).unwrap();
    area.spawn_at(&params, &t, 95.0, 185.0).unwrap();
    let mut scratch = SkiScratch::default();
    let mut steps = 0;
    while !area.skiers().is_empty() {
        let r = step(&params, &mut area, &mut t, &mut scratch, 0.5).unwrap();
        steps += 1;
        assert!(steps < 1000, "skier never stopped");
        if let Some(f) = r.finished.first() {
            assert_eq!(f.stop, StopReason::Stuck);
        }
    }
    let tr = &area.finished_tracks()[0];
    assert_eq!(tr.stop, Some(StopReason::Stuck));
    for &c in &tr.cells {
        assert!(
            (8..12).contains(&(c % 20)) && (10..14).contains(&(c / 20)),
            "left the island: {c}"
        );
    }
    // A run capped at 150 m stops there.
    let capped = SkiParams {
        max_run_length_m: 150.0,
        ..SkiParams::default()
    };
    let mut t = common::plane(20, 60, 10.0, 30.0);
    let mut area = SkiArea::new(&capped, &t, Terminus::Cells((1180..1200).collect()), 4).unwrap();
    area.spawn_at(&capped, &t, 100.0, 595.0).unwrap();
    run_out(&capped, &mut area, &mut t, 1.0, 1000);
    let tr = &area.finished_tracks()[0];
    assert_eq!(tr.stop, Some(StopReason::MaxLength));
    assert!(
        (150.0..155.0).contains(&tr.coarse_length_m),
        "{}",
        tr.coarse_length_m
    );
    assert!(tr.end_time_s.unwrap() - tr.start_time_s >= 150.0 / capped.speed_m_s - 1e-9);
}

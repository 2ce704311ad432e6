//! The session without a network: brushes, undo/redo, timeline, live avalanche and skier,
//! scenario changes, save and load, and refusals.

mod common;

use common::{session, snow_mean_altitude, steepest_cell};
use snowscape_editor::Session;
use snowscape_editor::project::ProjectDir;
use snowscape_editor::protocol::{BrushOp, BrushTarget, ClientMessage, ErrorCode, decode};
use snowscape_editor::session::{Out, Outgoing};
use snowscape_editor::wire::{Channel, decode_frame};

fn brush(
    stroke: u32,
    op: BrushOp,
    target: BrushTarget,
    c: usize,
    r: usize,
    strength: f64,
) -> ClientMessage {
    ClientMessage::Brush {
        stroke,
        op,
        target,
        col: c as f64,
        row: r as f64,
        radius_m: 100.0,
        strength,
        value: 0.0,
    }
}

/// Unstable snow brushed over the whole 128² test terrain, so that a skier has a run.
fn snow_everywhere(s: &mut Session) {
    for r in (8..120).step_by(6) {
        for c in (8..120).step_by(6) {
            let dab = ClientMessage::Brush {
                stroke: 1,
                op: BrushOp::Add,
                target: BrushTarget::Unstable,
                col: c as f64,
                row: r as f64,
                radius_m: 250.0,
                strength: 0.4,
                value: 0.0,
            };
            s.handle(dab, None, None).unwrap();
        }
    }
}

fn binary_channels(out: &[Out]) -> Vec<u8> {
    out.iter()
        .filter_map(|o| match o {
            Out::All(Outgoing::Binary(b)) | Out::Sender(Outgoing::Binary(b)) => {
                decode_frame(b).map(|f| f.channel)
            }
            _ => None,
        })
        .collect()
}

#[test]
fn brush_raises_depth_sends_dirty_tiles_and_undoes() {
    let mut s = session(128, 10.0);
    let i = s.terrain().geometry().index(40, 50);
    let before = s.terrain().depth_at(i);
    let out = s
        .handle(
            brush(1, BrushOp::Add, BrushTarget::All, 40, 50, 0.5),
            None,
            None,
        )
        .unwrap();
    s.handle(
        brush(1, BrushOp::Add, BrushTarget::All, 41, 50, 0.5),
        None,
        None,
    )
    .unwrap();
    let after = s.terrain().depth_at(i);
    assert!(after > before + 0.5, "{before} -> {after}");
    let chans = binary_channels(&out);
    assert_eq!(chans, vec![1, 2, 3, 4], "the four layer channels");
    for o in &out {
        if let Out::All(Outgoing::Binary(b)) = o {
            let f = decode_frame(b).unwrap();
            assert!(
                !f.full && f.tiles.len() < 4,
                "only dirty tiles: {}",
                f.tiles.len()
            );
        }
    }
    assert_eq!(s.summary().undo, 1, "dabs of one stroke are one undo step");
    s.handle(ClientMessage::Undo {}, None, None).unwrap();
    assert_eq!(s.terrain().depth_at(i), before);
    s.handle(ClientMessage::Redo {}, None, None).unwrap();
    assert_eq!(s.terrain().depth_at(i), after);
    let e = s.handle(ClientMessage::Redo {}, None, None).unwrap_err();
    assert_eq!(e.0, ErrorCode::InvalidValue);
}

#[test]
fn paint_brushes_paint_their_maps() {
    let mut s = session(128, 10.0);
    let out = s
        .handle(
            brush(1, BrushOp::Add, BrushTarget::SkiArea, 60, 60, 1.0),
            None,
            None,
        )
        .unwrap();
    assert_eq!(binary_channels(&out), vec![Channel::SkiArea as u8]);
    let i = s.terrain().geometry().index(60, 60);
    assert_eq!(s.paint().ski_area[i], 1.0);
    assert_eq!(s.terrain().depth_at(i), 0.0);
}

#[test]
fn timeline_steps_seeks_and_branches() {
    let mut s = session(128, 20.0);
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    let st = s.summary();
    assert_eq!(st.snapshots.len(), 3);
    assert!((st.day - 2.0).abs() < 0.5, "day {}", st.day);
    let vol2 = st.snow_volume_m3;
    s.handle(ClientMessage::Seek { index: 0 }, None, None)
        .unwrap();
    assert_eq!(s.summary().day, 0.0);
    // An edit at day 0 survives scrubbing away and back.
    s.handle(
        brush(5, BrushOp::Add, BrushTarget::Stable, 30, 30, 1.0),
        None,
        None,
    )
    .unwrap();
    let v0 = s.summary().snow_volume_m3;
    s.handle(ClientMessage::Seek { index: 2 }, None, None)
        .unwrap();
    assert_eq!(s.summary().snow_volume_m3, vol2);
    s.handle(ClientMessage::Seek { index: 0 }, None, None)
        .unwrap();
    assert_eq!(s.summary().snow_volume_m3, v0);
    // Stepping from day 0 drops the later snapshots.
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    assert_eq!(s.summary().snapshots.len(), 2);
    let e = s
        .handle(ClientMessage::Seek { index: 9 }, None, None)
        .unwrap_err();
    assert!(e.1.contains("snapshot 9"), "{}", e.1);
}

#[test]
fn triggered_avalanche_streams_flow_and_moves_snow_downhill() {
    let mut s = session(128, 10.0);
    let (c, r) = steepest_cell(&s);
    s.handle(
        brush(1, BrushOp::Add, BrushTarget::Unstable, c, r, 2.0),
        None,
        None,
    )
    .unwrap();
    s.handle(
        brush(1, BrushOp::Add, BrushTarget::Stable, c, r, 0.5),
        None,
        None,
    )
    .unwrap();
    let before = snow_mean_altitude(&s);
    let vol = s.summary().snow_volume_m3;
    let out = s
        .handle(
            ClientMessage::TriggerAvalanche {
                col: c as f64,
                row: r as f64,
            },
            None,
            None,
        )
        .unwrap();
    assert!(s.busy());
    assert!(binary_channels(&out).contains(&(Channel::Unstable as u8)));
    // Season steps wait for the flow to end.
    let e = s
        .handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap_err();
    assert_eq!(e.0, ErrorCode::Busy);
    let frames = s.run_live_to_end().unwrap();
    let flow_frames = binary_channels(&frames)
        .iter()
        .filter(|&&c| c == Channel::Flow as u8)
        .count();
    assert!(flow_frames > 5, "{flow_frames} flow frames");
    let after = snow_mean_altitude(&s);
    assert!(
        after < before - 1.0,
        "snow mean altitude {before} -> {after}"
    );
    let vol_after = s.summary().snow_volume_m3;
    assert!(
        vol_after <= vol * 1.0001 && vol_after > vol * 0.5,
        "{vol} -> {vol_after}"
    );
}

#[test]
fn avalanche_without_unstable_snow_is_refused() {
    let mut s = session(128, 10.0);
    let e = s
        .handle(
            ClientMessage::TriggerAvalanche {
                col: 10.0,
                row: 10.0,
            },
            None,
            None,
        )
        .unwrap_err();
    assert_eq!(e.0, ErrorCode::InvalidValue);
    assert!(e.1.contains("(10, 10)"), "{}", e.1);
    assert!(!s.busy());
}

#[test]
fn scenario_change_restarts_from_day_zero_and_bad_ones_are_refused() {
    let mut s = session(128, 10.0);
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    let mut sc = s.summary().scenario;
    sc["days"] = serde_json::json!(42.0);
    s.handle(
        ClientMessage::SetScenario {
            scenario: sc.clone(),
        },
        None,
        None,
    )
    .unwrap();
    let st = s.summary();
    assert_eq!((st.day, st.season_days, st.snapshots.len()), (0.0, 42.0, 1));
    sc["days"] = serde_json::json!(-3.0);
    let e = s
        .handle(ClientMessage::SetScenario { scenario: sc }, None, None)
        .unwrap_err();
    assert_eq!(e.0, ErrorCode::InvalidValue);
    let e = s
        .handle(
            ClientMessage::SetScenario {
                scenario: serde_json::json!({"nope": 1}),
            },
            None,
            None,
        )
        .unwrap_err();
    assert!(e.1.contains("nope"), "{}", e.1);
}

#[test]
fn save_and_load_round_trip_in_the_project_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let pd = ProjectDir::open(tmp.path()).unwrap();
    let mut s = session(128, 10.0);
    s.handle(ClientMessage::Step { days: 2.0 }, None, None)
        .unwrap();
    s.handle(
        brush(1, BrushOp::Add, BrushTarget::Powder, 50, 50, 1.0),
        None,
        None,
    )
    .unwrap();
    s.handle(
        brush(
            2,
            BrushOp::Add,
            BrushTarget::AvalancheProbability,
            20,
            20,
            0.3,
        ),
        None,
        None,
    )
    .unwrap();
    let out = s
        .handle(ClientMessage::Save { name: "p1".into() }, Some(&pd), None)
        .unwrap();
    // A save is a job: started, ended, then the "saved" message with the files written.
    let messages: Vec<serde_json::Value> = out
        .iter()
        .filter_map(|o| match o {
            Out::All(Outgoing::Text(t)) => serde_json::from_str::<serde_json::Value>(t).ok(),
            _ => None,
        })
        .collect();
    let phases: Vec<&serde_json::Value> = messages
        .iter()
        .filter(|m| m["type"] == "job")
        .map(|m| &m["phase"])
        .collect();
    assert_eq!(phases, ["started", "ended"], "{messages:?}");
    let saved = messages
        .iter()
        .find(|m| m["what"] == "saved")
        .expect("a saved message");
    assert!(
        saved["files"].as_array().is_some_and(|f| f.len() >= 5),
        "{saved}"
    );
    assert!(tmp.path().join("projects/p1/checkpoint.bin").is_file());
    // history.json: what the user did, in order, with its keys.
    let history: serde_json::Value = serde_json::from_slice(
        &std::fs::read(tmp.path().join("projects/p1/history.json")).unwrap(),
    )
    .unwrap();
    let actions: Vec<&str> = history["actions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["action"].as_str().unwrap())
        .collect();
    assert_eq!(actions, ["step", "brush", "brush"], "{history}");
    assert_eq!(history["actions"][1]["target"], "powder");
    assert_eq!(history["day"], s.summary().day);
    let saved = s.summary();
    let layers = s.terrain().snow.clone();
    let paint = s.paint().clone();
    s.handle(ClientMessage::Seek { index: 0 }, None, None)
        .unwrap();
    s.handle(ClientMessage::Load { name: "p1".into() }, Some(&pd), None)
        .unwrap();
    assert_eq!(s.summary().day, saved.day);
    assert_eq!(s.terrain().snow, layers);
    let actions: Vec<&str> = s
        .history()
        .iter()
        .map(|a| match a {
            snowscape_editor::history::Action::Step { .. } => "step",
            snowscape_editor::history::Action::Brush { .. } => "brush",
            snowscape_editor::history::Action::Load { .. } => "load",
            _ => "other",
        })
        .collect();
    assert_eq!(actions, ["step", "brush", "brush", "load"]);
    assert_eq!(s.paint(), &paint);
    let e = s
        .handle(
            ClientMessage::Load {
                name: "absent".into(),
            },
            Some(&pd),
            None,
        )
        .unwrap_err();
    assert_eq!(e.0, ErrorCode::NotFound);
    // The decoder refuses names that could leave the folder before the session sees them.
    assert!(decode(br#"{"type":"load","name":"../p1"}"#, 1000).is_err());
}

#[test]
fn scenario_paths_that_leave_the_project_folder_are_refused_on_set_save_and_load() {
    let tmp = tempfile::tempdir().unwrap();
    let pd = ProjectDir::open(tmp.path()).unwrap();
    let mut s = session(64, 10.0);
    // From the page: refused before anything changes, naming the value.
    let mut sc = s.summary().scenario;
    sc["forcing"] = serde_json::json!("/etc/passwd");
    let (code, message) = s
        .handle(ClientMessage::SetScenario { scenario: sc }, Some(&pd), None)
        .unwrap_err();
    assert_eq!(code, ErrorCode::BadPath);
    assert!(
        message.contains("scenario.forcing") && message.contains("\"/etc/passwd\""),
        "{message}"
    );
    assert!(s.winter().scenario().forcing.is_none());
    // A saved project whose scenario.toml was edited to name a file outside: not loaded.
    s.handle(ClientMessage::Save { name: "p2".into() }, Some(&pd), None)
        .unwrap();
    let file = tmp.path().join("projects/p2/scenario.toml");
    for bad in ["/etc/passwd", "../../../etc/passwd"] {
        let text = std::fs::read_to_string(&file).unwrap();
        let text: String = text
            .lines()
            .filter(|l| !l.starts_with("forcing"))
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(&file, format!("forcing = {bad:?}\n{text}\n")).unwrap();
        let (code, message) = s
            .handle(ClientMessage::Load { name: "p2".into() }, Some(&pd), None)
            .unwrap_err();
        assert_eq!(code, ErrorCode::BadPath, "{message}");
        assert!(message.contains(&format!("{bad:?}")), "{message}");
    }
}

#[test]
fn launched_skier_moves_and_packs_snow() {
    let mut s = session(128, 10.0);
    snow_everywhere(&mut s);
    let (c, r) = steepest_cell(&s);
    s.handle(
        ClientMessage::LaunchSkier {
            col: c as f64,
            row: r as f64,
        },
        None,
        None,
    )
    .unwrap();
    let out = s.run_live_to_end().unwrap();
    let positions: Vec<serde_json::Value> = out
        .iter()
        .filter_map(|o| match o {
            Out::All(Outgoing::Text(t)) => serde_json::from_str::<serde_json::Value>(t).ok(),
            _ => None,
        })
        .filter(|v| v["type"] == "skiers")
        .collect();
    assert!(positions.len() > 3, "{} skier frames", positions.len());
    let first = &positions[0]["positions"][0];
    let later = &positions[positions.len() / 2]["positions"][0];
    assert_ne!(first, later, "the skier moved");
    let stable: f32 = s.terrain().snow[1].iter().sum();
    assert!(stable > 0.0, "skiing packs unstable snow into stable snow");
}

#[test]
fn painted_skiers_run_on_the_season_path() {
    let mut s = session(128, 10.0);
    snow_everywhere(&mut s);
    let (c, r) = steepest_cell(&s);
    s.handle(
        brush(2, BrushOp::Add, BrushTarget::SkiArea, c, r, 1.0),
        None,
        None,
    )
    .unwrap();
    let runs = s.winter().ski_stats().runs;
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    let w = s.winter();
    assert!(
        w.ski_stats().runs > runs,
        "painted skiers are counted as the season's skier runs ({} runs)",
        w.ski_stats().runs
    );
    assert!(w.ski_stats().steps > 0 && w.ski_stats().distance_m > 0.0);
}

/// Painted release probability is a hazard source of the season's scheduler: a step starts
/// painted avalanches during its days, recorded with the `painted` trigger.
#[test]
fn painted_release_probability_starts_the_seasons_avalanches() {
    let mut s = session(128, 10.0);
    snow_everywhere(&mut s);
    let (c, r) = steepest_cell(&s);
    s.handle(
        brush(
            3,
            BrushOp::Add,
            BrushTarget::AvalancheProbability,
            c,
            r,
            1.0,
        ),
        None,
        None,
    )
    .unwrap();
    let from = s.winter().day();
    s.handle(ClientMessage::Step { days: 2.0 }, None, None)
        .unwrap();
    let w = s.winter();
    let painted: Vec<_> = w
        .avalanches()
        .iter()
        .filter(|a| a.trigger == snowscape_season::avalanches::Trigger::Painted)
        .collect();
    assert!(!painted.is_empty(), "{:?}", w.avalanches());
    assert!(painted.iter().all(|a| a.day > from && a.day <= w.day()));
}

#[test]
fn a_scenario_that_is_not_a_json_object_is_refused() {
    let mut s = session(128, 10.0);
    let mut good = s.summary().scenario;
    for bad in [
        serde_json::json!([]),
        serde_json::json!([1, 2, 3]),
        serde_json::json!(null),
        serde_json::json!(7),
        serde_json::json!("days"),
    ] {
        let e = s
            .handle(ClientMessage::SetScenario { scenario: bad }, None, None)
            .unwrap_err();
        assert_eq!(e.0, ErrorCode::InvalidValue);
        assert!(e.1.contains("must be a JSON object"), "{}", e.1);
    }
    good["parameters"] = serde_json::json!([]);
    let e = s
        .handle(ClientMessage::SetScenario { scenario: good }, None, None)
        .unwrap_err();
    assert_eq!(e.0, ErrorCode::InvalidValue);
    assert!(e.1.contains("scenario.parameters"), "{}", e.1);
    assert_eq!(s.summary().season_days, 10.0, "the season is unchanged");
}

/// Issue 19 item 3: the page's parameters get the scenario files' validation, before they
/// take effect (each case once aborted the process, hung every tab, or broke every step).
#[test]
fn hostile_parameters_from_the_page_are_refused_before_they_take_effect() {
    let mut s = session(128, 10.0);
    let good = s.summary().scenario;
    for (path, value, needle) in [
        (
            &["parameters", "powder_diffusion", "k_m"][..],
            serde_json::json!(1e9),
            "k_m",
        ),
        (
            &["parameters", "environment", "wind", "ordered_sweeps"][..],
            serde_json::json!(1_000_000_000u64),
            "ordered_sweeps",
        ),
        (
            &["skiers", "per_day"][..],
            serde_json::json!(1e9),
            "per_day",
        ),
        (
            &["events", "melt_and_state"][..],
            serde_json::json!(1e9),
            "melt_and_state",
        ),
        (
            &["events", "wind_transport"][..],
            serde_json::json!(-1.0),
            "wind_transport",
        ),
        (
            &["parameters", "melt", "k_melt"][..],
            serde_json::json!(-1.0),
            "k_melt = -1",
        ),
        (
            &["parameters", "stability", "t_cool"][..],
            serde_json::json!(1e9),
            "t_cool",
        ),
        (
            &["snapshot_every_days"][..],
            serde_json::json!(1e-9),
            "snapshot_every_days",
        ),
    ] {
        let mut bad = good.clone();
        let mut at = &mut bad;
        for k in &path[..path.len() - 1] {
            at = &mut at[*k];
        }
        at[path[path.len() - 1]] = value;
        let e = s
            .handle(ClientMessage::SetScenario { scenario: bad }, None, None)
            .unwrap_err();
        assert_eq!(e.0, ErrorCode::InvalidValue, "{path:?}: {}", e.1);
        assert!(e.1.contains(needle), "{path:?}: {}", e.1);
    }
    assert_eq!(s.summary().season_days, 10.0, "the season is unchanged");
    // The session still steps.
    s.handle(ClientMessage::Step { days: 0.5 }, None, None)
        .unwrap();
}

#[test]
fn the_timeline_keeps_within_its_memory_budget_and_keeps_the_first_snapshot() {
    let mut s = session(128, 30.0);
    // Snapshots are packed: their sizes vary with the snow; the budget here holds the first
    // and about two more of the first step's size.
    let first = s.summary().snapshot_bytes;
    s.handle(ClientMessage::Step { days: 0.5 }, None, None)
        .unwrap();
    let one = s.summary().snapshot_bytes - first;
    let budget = first + 2 * one + one / 2;
    s.set_snapshot_budget(budget);
    let mut notices = Vec::new();
    for _ in 0..12 {
        let out = s
            .handle(ClientMessage::Step { days: 0.5 }, None, None)
            .unwrap();
        notices.extend(out.iter().filter_map(|o| match o {
            Out::All(Outgoing::Text(t)) if t.contains("\"type\":\"notice\"") => Some(t.clone()),
            _ => None,
        }));
        let st = s.summary();
        assert!(st.snapshots.len() <= 3, "{} snapshots", st.snapshots.len());
        assert!(st.snapshots.len() >= 2, "{} snapshots", st.snapshots.len());
        assert!(
            st.snapshot_bytes <= st.snapshot_budget_bytes || st.snapshots.len() == 2,
            "{} bytes kept, budget {}",
            st.snapshot_bytes,
            st.snapshot_budget_bytes
        );
        assert_eq!(st.snapshots[0], 0.0, "the first snapshot stays");
        assert_eq!(st.current, st.snapshots.len() - 1);
    }
    let st = s.summary();
    let kept = st.snapshots.len();
    assert_eq!(st.snapshots_dropped + kept, 14, "14 snapshots made");
    assert!(
        (st.snapshots[kept - 1] - st.day).abs() < 1e-9
            && st.snapshots[kept - 2] < st.snapshots[kept - 1]
    );
    assert!(
        !notices.is_empty() && notices.len() <= st.snapshots_dropped,
        "a notice per step that dropped some"
    );
    assert!(notices[0].contains("memory budget"), "{}", notices[0]);
    // A new scenario restarts from the first snapshot and keeps the budget.
    let mut sc = st.scenario.clone();
    sc["days"] = serde_json::json!(20.0);
    s.handle(ClientMessage::SetScenario { scenario: sc }, None, None)
        .unwrap();
    let st = s.summary();
    assert_eq!((st.day, st.snapshots.len()), (0.0, 1));
    assert_eq!(st.snapshot_budget_bytes, budget);
}

/// A brush stroke over the whole terrain (every cell of the total depth).
fn big_stroke(s: &mut Session, stroke: u32) -> Vec<Out> {
    let g = s.terrain().geometry().clone();
    let dab = ClientMessage::Brush {
        stroke,
        op: BrushOp::Add,
        target: BrushTarget::Unstable,
        col: g.width() as f64 / 2.0,
        row: g.height() as f64 / 2.0,
        radius_m: g.width() as f64 * g.cell_size_x(),
        strength: 0.1,
        value: 0.0,
    };
    s.handle(dab, None, None).expect("a stroke")
}

fn notices(out: &[Out]) -> Vec<String> {
    out.iter()
        .filter_map(|o| match o {
            Out::All(Outgoing::Text(t)) if t.contains("\"type\":\"notice\"") => Some(t.clone()),
            _ => None,
        })
        .collect()
}

#[test]
fn the_undo_history_keeps_within_its_byte_budget_dropping_the_oldest_first() {
    let mut s = session(64, 10.0);
    big_stroke(&mut s, 1);
    let one = s.undo_bytes();
    assert!(
        one > 64 * 64 * 16,
        "a whole-terrain stroke records every cell: {one} bytes"
    );
    s.set_undo_budget(3 * one + one / 2);
    let mut told = Vec::new();
    for stroke in 2..=20 {
        let before = s.terrain().snow.clone();
        told.extend(notices(&big_stroke(&mut s, stroke)));
        let st = s.summary();
        assert!(
            s.undo_bytes() <= 3 * one + one / 2,
            "stroke {stroke}: {} bytes kept",
            s.undo_bytes()
        );
        assert!(st.undo <= 3, "{} strokes kept", st.undo);
        // The newest stroke is always undoable, exactly.
        if stroke == 20 {
            s.handle(ClientMessage::Undo {}, None, None).unwrap();
            assert!(s.terrain().snow == before, "undo restores the last stroke");
        }
    }
    assert!(!told.is_empty(), "the tabs are told");
    assert!(told[0].contains("undo history"), "{}", told[0]);
    // A stroke that alone is larger than the budget is not recorded (nothing to undo), and
    // says so.
    s.set_undo_budget(one / 4);
    assert_eq!(s.summary().undo, 0);
    let out = big_stroke(&mut s, 21);
    let n = notices(&out);
    assert!(n.iter().any(|m| m.contains("cannot be undone")), "{n:?}");
    big_stroke(&mut s, 21);
    assert_eq!((s.summary().undo, s.undo_bytes()), (0, 0));
    let (code, message) = s.handle(ClientMessage::Undo {}, None, None).unwrap_err();
    assert_eq!(code, ErrorCode::InvalidValue);
    assert!(message.contains("nothing to undo"));
    assert_eq!(
        snowscape_editor::session::UNDO_BUDGET_BYTES,
        256 << 20,
        "the documented budget"
    );
}

#[test]
fn brush_radii_beyond_the_terrain_are_refused() {
    let mut s = session(64, 10.0);
    let before = s.terrain().snow.clone();
    for radius_m in [1e5, 64.0 * 20.0 * 1.5] {
        let dab = ClientMessage::Brush {
            stroke: 1,
            op: BrushOp::Add,
            target: BrushTarget::Powder,
            col: 32.0,
            row: 32.0,
            radius_m,
            strength: 0.5,
            value: 0.0,
        };
        let (code, message) = s.handle(dab, None, None).unwrap_err();
        assert_eq!(code, ErrorCode::InvalidValue);
        assert!(
            message.contains(&format!("radius_m = {radius_m}")),
            "{message}"
        );
        assert!(
            message.contains("1810 m"),
            "names the terrain's extent: {message}"
        );
    }
    assert!(s.terrain().snow == before, "nothing changed");
    assert_eq!(s.summary().undo, 0);
}

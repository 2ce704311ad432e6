//! Jobs without a network: a season step handed out by `Session::start` runs on another
//! thread while the session answers reads and refuses changes with `busy`; `cancel` drops it
//! and leaves the season where it was; a finished step is the season a single `run_until`
//! gives; `cancel` ends a live avalanche with its snow deposited.

mod common;

use common::{session, steepest_cell};
use snowscape_editor::job::{JobOutcome, JobPhase};
use snowscape_editor::protocol::{BrushOp, BrushTarget, ClientMessage, ErrorCode};
use snowscape_editor::session::{Out, Outgoing, Started};

fn texts(out: &[Out]) -> Vec<serde_json::Value> {
    out.iter()
        .filter_map(|o| match o {
            Out::All(Outgoing::Text(t)) | Out::Sender(Outgoing::Text(t)) => {
                serde_json::from_str(t).ok()
            }
            _ => None,
        })
        .collect()
}

fn dab(stroke: u32, target: BrushTarget, c: usize, r: usize, strength: f64) -> ClientMessage {
    ClientMessage::Brush {
        stroke,
        op: BrushOp::Add,
        target,
        col: c as f64,
        row: r as f64,
        radius_m: 150.0,
        strength,
        value: 0.0,
    }
}

#[test]
fn a_step_runs_on_a_worker_while_the_session_answers_and_refuses_changes() {
    let mut s = session(128, 20.0);
    let Started::Job(job, started) = s
        .start(ClientMessage::Step { days: 5.0 }, None, None)
        .unwrap()
    else {
        panic!("a step is a job");
    };
    assert_eq!(texts(&started)[0]["type"], "job");
    assert_eq!(texts(&started)[0]["phase"], "started");
    let id = job.id();
    let worker = std::thread::spawn(move || {
        let mut reports = 0;
        let outcome = job.run(&mut |_| reports += 1);
        (outcome, reports)
    });
    // While it runs: the state says so, reads are answered, changes wait.
    let st = s.summary();
    assert!(st.busy);
    assert_eq!(st.job.as_ref().map(|j| j.id), Some(id));
    assert!(s.probe(10, 10).is_ok());
    assert!(
        s.handle(ClientMessage::Probe { col: 10, row: 10 }, None, None)
            .is_ok()
    );
    assert!(
        s.handle(ClientMessage::Resync {}, None, None)
            .unwrap()
            .len()
            > 5
    );
    for change in [
        ClientMessage::Step { days: 1.0 },
        dab(1, BrushTarget::Powder, 20, 20, 0.5),
        ClientMessage::Seek { index: 0 },
        ClientMessage::Undo {},
    ] {
        let e = s.handle(change, None, None).unwrap_err();
        assert_eq!(e.0, ErrorCode::Busy, "{}", e.1);
        assert!(e.1.contains("season step"), "{}", e.1);
    }
    let (outcome, _) = worker.join().unwrap();
    assert!(matches!(outcome, JobOutcome::Stepped { .. }));
    let out = s.finish_job(id, outcome);
    let msgs = texts(&out);
    assert!(
        msgs.iter()
            .any(|m| m["type"] == "job" && m["phase"] == "ended")
    );
    let st = s.summary();
    assert!(!st.busy && st.job.is_none());
    assert!((st.day - 5.0).abs() < 0.5, "day {}", st.day);
    assert_eq!(st.snapshots.len(), 2);
}

#[test]
fn a_cancelled_step_leaves_the_season_where_it_was() {
    let mut s = session(128, 20.0);
    s.handle(dab(1, BrushTarget::Stable, 40, 40, 1.0), None, None)
        .unwrap();
    let volume = s.summary().snow_volume_m3;
    let Started::Job(job, _) = s
        .start(ClientMessage::Step { days: 10.0 }, None, None)
        .unwrap()
    else {
        panic!("a step is a job");
    };
    let id = job.id();
    let out = s.handle(ClientMessage::Cancel {}, None, None).unwrap();
    assert_eq!(texts(&out)[0]["phase"], "cancelling");
    assert_eq!(s.job().map(|j| j.phase), Some(JobPhase::Cancelling));
    let outcome = job.run(&mut |_| {});
    assert!(matches!(outcome, JobOutcome::Cancelled));
    let msgs = texts(&s.finish_job(id, outcome));
    assert!(
        msgs.iter()
            .any(|m| m["type"] == "job" && m["phase"] == "cancelled")
    );
    let st = s.summary();
    assert_eq!((st.day, st.snapshots.len(), st.busy), (0.0, 1, false));
    assert_eq!(st.snow_volume_m3, volume, "the edit before the step stays");
    // Nothing left to cancel; and the session steps again.
    let e = s.handle(ClientMessage::Cancel {}, None, None).unwrap_err();
    assert_eq!(e.0, ErrorCode::InvalidValue);
    s.handle(ClientMessage::Step { days: 1.0 }, None, None)
        .unwrap();
    assert!(s.summary().day >= 1.0);
}

#[test]
fn a_step_in_slices_is_the_season_of_one_run() {
    let mut s = session(128, 20.0);
    let mut reference = s.winter().clone();
    s.handle(ClientMessage::Step { days: 4.0 }, None, None)
        .unwrap();
    reference.run_until(4.0).unwrap();
    assert_eq!(s.winter().day(), reference.day());
    assert_eq!(s.terrain().snow, reference.terrain.snow);
}

#[test]
fn cancel_ends_a_live_avalanche_with_its_snow_deposited() {
    let mut s = session(128, 10.0);
    let (c, r) = steepest_cell(&s);
    s.handle(dab(1, BrushTarget::Unstable, c, r, 2.0), None, None)
        .unwrap();
    let volume = s.summary().snow_volume_m3;
    s.handle(
        ClientMessage::TriggerAvalanche {
            col: c as f64,
            row: r as f64,
        },
        None,
        None,
    )
    .unwrap();
    for _ in 0..3 {
        s.tick().unwrap();
    }
    assert!(s.busy());
    let msgs = texts(&s.handle(ClientMessage::Cancel {}, None, None).unwrap());
    let av = msgs
        .iter()
        .find(|m| m["type"] == "avalanche")
        .expect("the avalanche's last message");
    assert_eq!(
        (&av["phase"], &av["stop"]),
        (&"ended".into(), &"cancelled".into())
    );
    assert!(!s.busy());
    let after = s.summary().snow_volume_m3;
    assert!(
        (after - volume).abs() < volume * 1e-3,
        "the flowing snow deposited: {volume} -> {after}"
    );
}

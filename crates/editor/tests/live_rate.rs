//! Measures the live avalanche's update rate on a 1024² terrain: frames (records) per second
//! computed and encoded by the session, and bytes per frame (dirty tiles only). Ignored by
//! default (it takes a minute); run it with
//! `cargo test --release -p snowscape-editor --test live_rate -- --ignored --nocapture`.
//! It prints numbers and asserts only that the flow produced frames.

mod common;

use common::{session, steepest_cell};
use snowscape_editor::protocol::{BrushOp, BrushTarget, ClientMessage};
use snowscape_editor::session::{Out, Outgoing};
use std::time::Instant;

#[test]
#[ignore = "a 1024² measurement; run with --ignored --nocapture"]
fn live_avalanche_updates_per_second_on_1024() {
    let t = Instant::now();
    let mut s = session(1024, 100.0);
    println!(
        "season set-up (environment precompute) {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let (c, r) = steepest_cell(&s);
    let dab = ClientMessage::Brush {
        stroke: 1,
        op: BrushOp::Add,
        target: BrushTarget::Unstable,
        col: c as f64,
        row: r as f64,
        radius_m: 400.0,
        strength: 2.0,
        value: 0.0,
    };
    s.handle(dab, None, None).unwrap();
    // The start (rupture, release, the first frames) is answered on the request path: it
    // must stay short.
    let start = Instant::now();
    s.handle(
        ClientMessage::TriggerAvalanche {
            col: c as f64,
            row: r as f64,
        },
        None,
        None,
    )
    .unwrap();
    println!(
        "1024²: the trigger_avalanche answer took {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    let t = Instant::now();
    let (mut frames, mut bytes, mut max_bytes) = (0usize, 0usize, 0usize);
    while s.busy() && frames < 400 {
        for o in s.tick().unwrap() {
            if let Out::All(Outgoing::Binary(b)) = o {
                frames += 1;
                bytes += b.len();
                max_bytes = max_bytes.max(b.len());
            }
        }
    }
    let dt = t.elapsed().as_secs_f64();
    println!(
        "1024²: {frames} flow frames in {dt:.2} s = {:.1} updates/s; mean {:.1} KiB, max {:.1} KiB per frame (full grid would be {} KiB)",
        frames as f64 / dt,
        bytes as f64 / frames.max(1) as f64 / 1024.0,
        max_bytes as f64 / 1024.0,
        1024 * 1024 * 2 / 1024
    );
    assert!(frames > 0);
}

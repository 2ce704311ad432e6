//! The season driver ([`snowscape::simulation`]): its schedules fire at their days, a run stops
//! exactly where a single `run_until` would, a cancel leaves a state that runs on, and a run
//! checkpointed every few days and resumed ends with the bytes of an uninterrupted one.

use snowscape::season::scenario::Scenario;
use snowscape::season::winter::Winter;
use snowscape::simulation::{Actuation, Control, Schedule, Simulation, StopReason, Unattended};
use snowscape::terrain::{Grid, GridGeometry, LayeredTerrain};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const DAYS: f64 = 8.0;

/// A 48x48 mountain of 20 m cells, 600 m to 2600 m.
fn mountain() -> LayeredTerrain {
    let n = 48;
    let g = GridGeometry::square(n, n, 20.0).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        let (x, y) = (c as f32 / n as f32 - 0.5, r as f32 / n as f32 - 0.5);
        let d = (x * x + y * y).sqrt();
        600.0 + 2000.0 * (1.0 - 2.0 * d).max(0.0).powf(1.5)
    }))
}

/// A short season on the mountain (a coarse sky and sun: the driver, not the environment, is
/// under test).
fn winter() -> Winter {
    Winter::new(scenario(), mountain()).unwrap()
}

fn scenario() -> Scenario {
    let mut s = Scenario {
        days: DAYS,
        seed: 11,
        latitude_deg: Some(46.5),
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    s
}

fn checkpoint(w: &Winter) -> Vec<u8> {
    let mut bytes = Vec::new();
    w.write_checkpoint(&mut bytes).unwrap();
    bytes
}

fn resume(bytes: &[u8]) -> Winter {
    Winter::resume(scenario(), mountain(), &mut &bytes[..]).unwrap()
}

/// Counts its progress reports and chunks; cancels after `cancel_after` reports.
#[derive(Default)]
struct Counting {
    reports: Vec<f64>,
    chunks: usize,
    cancel_after: Option<usize>,
    sleep: Duration,
}

impl Control for Counting {
    fn progress(&mut self, day: f64, _stop_time: f64) {
        self.reports.push(day);
    }
    fn cancelled(&mut self) -> bool {
        self.cancel_after.is_some_and(|n| self.reports.len() >= n)
    }
    fn run_chunk(&mut self, chunk: &mut (dyn FnMut() + Send)) {
        self.chunks += 1;
        std::thread::sleep(self.sleep);
        chunk()
    }
}

#[test]
fn time_schedules_fire_at_their_days_on_the_state_a_single_run_passes() {
    let start = winter();
    let mut w = start.clone();
    let mut fired: Vec<(char, Actuation, f64, Vec<u8>)> = Vec::new();
    let reason = Simulation::new(&mut w, DAYS)
        .output('t', Schedule::TimeInterval(2.5))
        .output(
            's',
            Schedule::SpecificTimes(vec![3.3, 0.7, 3.3, 9.0, f64::NAN]),
        )
        .run_with(&mut Unattended, |k, at, w| {
            fired.push((k, at, w.day(), checkpoint(w)));
            Ok::<(), std::convert::Infallible>(())
        })
        .unwrap();
    assert!(matches!(reason, StopReason::SeasonEnded { day } if day >= DAYS));
    let got: Vec<(char, usize, f64)> = fired
        .iter()
        .map(|(k, a, _, _)| (*k, a.index, a.day))
        .collect();
    assert_eq!(
        got,
        [
            ('s', 0, 0.7),
            ('t', 0, 2.5),
            ('s', 1, 3.3),
            ('t', 1, 5.0),
            ('t', 2, 7.5)
        ]
    );
    // Each output saw the season as one run_until to its day leaves it.
    for (_, at, day, bytes) in &fired {
        let mut reference = start.clone();
        reference.run_until(at.day).unwrap();
        assert_eq!(*day, reference.day());
        assert!(*day >= at.day);
        assert!(
            *bytes == checkpoint(&reference),
            "the state at day {}",
            at.day
        );
    }
    // The whole run is the season of one run_until, bit for bit.
    let mut reference = start.clone();
    reference.run_until(DAYS).unwrap();
    assert!(checkpoint(&w) == checkpoint(&reference));
}

#[test]
fn a_run_stops_exactly_at_its_stop_time_and_chunks_change_nothing() {
    let start = winter();
    let mut reference = start.clone();
    reference.run_until(3.1).unwrap();
    let mut chunks = Vec::new();
    for chunk in [0.05, 1.0, f64::INFINITY] {
        let mut w = start.clone();
        let mut control = Counting::default();
        let reason = Simulation::new(&mut w, 3.1)
            .max_chunk_days(chunk)
            .run(&mut control)
            .unwrap();
        assert_eq!(reason, StopReason::StopTime { day: w.day() });
        assert_eq!(w.day(), reference.day());
        assert!(
            checkpoint(&w) == checkpoint(&reference),
            "chunks of {chunk} days"
        );
        // A report after every chunk, the last at the stop.
        assert_eq!(control.reports.len(), control.chunks);
        assert_eq!(control.reports.last(), Some(&w.day()));
        // A chunk ends at the first event past its end: never more chunks than the stretch
        // holds.
        if chunk == f64::INFINITY {
            assert_eq!(control.chunks, 1);
        } else {
            assert!(
                control.chunks as f64 <= (3.1 / chunk).ceil(),
                "{}",
                control.chunks
            );
        }
        chunks.push(control.chunks);
    }
    assert!(chunks[0] > chunks[1] && chunks[1] > chunks[2], "{chunks:?}");
    // A stop time past the season's end ends with the season.
    let mut w = reference;
    let reason = Simulation::new(&mut w, 1e9).run(&mut Unattended).unwrap();
    assert_eq!(reason, StopReason::SeasonEnded { day: w.day() });
    assert!(w.finished());
}

#[test]
fn iteration_and_wall_time_schedules_and_the_wall_time_limit() {
    let start = winter();
    let mut w = start.clone();
    let mut control = Counting {
        sleep: Duration::from_millis(20),
        ..Counting::default()
    };
    let mut fired: Vec<(char, Actuation)> = Vec::new();
    let started = Instant::now();
    let reason = Simulation::new(&mut w, 2.0)
        .max_chunk_days(0.2)
        .progress(Schedule::IterationInterval(3))
        .output('i', Schedule::IterationInterval(2))
        .output('w', Schedule::WallTimeInterval(Duration::from_millis(50)))
        .output('n', Schedule::WallTimeInterval(Duration::from_secs(3600)))
        .run_with(&mut control, |k, at, _| {
            fired.push((k, at));
            Ok::<(), std::convert::Infallible>(())
        })
        .unwrap();
    assert!(matches!(reason, StopReason::StopTime { .. }));
    let chunks = control.chunks;
    assert!(chunks >= 5, "{chunks} chunks");
    assert_eq!(control.reports.len(), chunks / 3);
    let of = |key| fired.iter().filter(|(k, _)| *k == key).count();
    assert_eq!(of('i'), chunks / 2);
    // 20 ms a chunk or more, at least 5 chunks: 50 ms pass at least once; and no more firings
    // than 50 ms fit in the run's wall time.
    let wall = started.elapsed();
    let walls = of('w');
    assert!(walls >= 1, "{chunks} chunks in {wall:?}");
    assert!(
        walls as u128 <= wall.as_millis() / 50,
        "{walls} firings in {wall:?}"
    );
    assert_eq!(of('n'), 0);
    let indices: Vec<usize> = fired
        .iter()
        .filter(|(k, _)| *k == 'w')
        .map(|(_, a)| a.index)
        .collect();
    assert_eq!(indices, (0..indices.len()).collect::<Vec<_>>());

    // The wall-time limit ends the run between chunks, before its stop time.
    let mut w = start.clone();
    let mut control = Counting {
        sleep: Duration::from_millis(30),
        ..Counting::default()
    };
    let reason = Simulation::new(&mut w, DAYS)
        .max_chunk_days(0.1)
        .wall_time_limit(Duration::from_millis(100))
        .run(&mut control)
        .unwrap();
    let StopReason::WallTimeLimit { day, elapsed } = reason else {
        panic!("{reason:?}");
    };
    assert_eq!(day, w.day());
    assert!(day < DAYS && elapsed >= Duration::from_millis(100));
    // 30 ms a chunk: 100 ms are over after the fourth at the latest.
    assert!((1..=4).contains(&control.chunks), "{}", control.chunks);
}

/// Raises its interrupt flag inside the `at`-th chunk, as Ctrl-C would.
struct Interrupting {
    flag: Arc<AtomicBool>,
    chunks: usize,
    at: usize,
}

impl Control for Interrupting {
    fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(self.flag.clone())
    }
    fn run_chunk(&mut self, chunk: &mut (dyn FnMut() + Send)) {
        self.chunks += 1;
        if self.chunks == self.at {
            self.flag.store(true, Ordering::SeqCst);
        }
        chunk()
    }
}

#[test]
fn a_cancel_stops_between_chunks_and_the_state_runs_on_bit_identically() {
    let start = winter();
    let mut reference = start.clone();
    reference.run_until(DAYS).unwrap();

    // Cancelled after the fourth chunk of half a day.
    let mut w = start.clone();
    let mut control = Counting {
        cancel_after: Some(4),
        ..Counting::default()
    };
    let reason = Simulation::new(&mut w, DAYS)
        .max_chunk_days(0.5)
        .run(&mut control)
        .unwrap();
    assert_eq!(reason, StopReason::Cancelled { day: w.day() });
    assert_eq!(control.chunks, 4);
    assert!(w.day() >= 2.0 && w.day() < DAYS);
    let mut resumed = resume(&checkpoint(&w));
    let reason = Simulation::new(&mut resumed, DAYS)
        .run(&mut Unattended)
        .unwrap();
    assert!(matches!(reason, StopReason::SeasonEnded { .. }));
    assert!(checkpoint(&resumed) == checkpoint(&reference));

    // The interrupt flag stops the third chunk before its first event: the season stays at the
    // second chunk's end, and runs on from there.
    let mut w = start.clone();
    let mut control = Interrupting {
        flag: Arc::new(AtomicBool::new(false)),
        chunks: 0,
        at: 3,
    };
    let mut two_chunks = start.clone();
    two_chunks.run_until(0.5).unwrap();
    let reason = Simulation::new(&mut w, DAYS)
        .max_chunk_days(0.25)
        .run(&mut control)
        .unwrap();
    assert_eq!(
        reason,
        StopReason::Cancelled {
            day: two_chunks.day()
        }
    );
    assert!(checkpoint(&w) == checkpoint(&two_chunks));
    let mut resumed = resume(&checkpoint(&w));
    Simulation::new(&mut resumed, DAYS)
        .run(&mut Unattended)
        .unwrap();
    assert!(checkpoint(&resumed) == checkpoint(&reference));
}

#[test]
fn checkpoints_every_few_days_then_resume_give_the_uninterrupted_bytes() {
    let start = winter();
    let mut reference = start.clone();
    Simulation::new(&mut reference, DAYS)
        .run(&mut Unattended)
        .unwrap();

    // Checkpoints every 1.5 days of a run stopped at day 5 (as `--stop-at 5` would).
    let mut w = start.clone();
    let mut saved: Vec<(f64, Vec<u8>)> = Vec::new();
    let reason = Simulation::new(&mut w, 5.0)
        .output((), Schedule::TimeInterval(1.5))
        .run_with(&mut Unattended, |(), at, w| {
            saved.push((at.day, checkpoint(w)));
            Ok::<(), std::convert::Infallible>(())
        })
        .unwrap();
    assert!(matches!(reason, StopReason::StopTime { .. }));
    let days: Vec<f64> = saved.iter().map(|(d, _)| *d).collect();
    assert_eq!(days, [1.5, 3.0, 4.5]);
    // Each checkpoint, resumed, ends the season with the uninterrupted bytes.
    for (day, bytes) in &saved {
        let mut resumed = resume(bytes);
        let mut fired = Vec::new();
        Simulation::new(&mut resumed, DAYS)
            .output((), Schedule::TimeInterval(1.5))
            .run_with(&mut Unattended, |(), at, _| {
                fired.push(at.day);
                Ok::<(), std::convert::Infallible>(())
            })
            .unwrap();
        assert!(
            checkpoint(&resumed) == checkpoint(&reference),
            "from day {day}"
        );
        // The resumed run fires only the days after its start.
        assert!(fired.iter().all(|d| d > day), "{fired:?} from {day}");
        assert_eq!(fired.last(), Some(&7.5));
    }
}

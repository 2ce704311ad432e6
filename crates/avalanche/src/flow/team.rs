//! A second thread that takes half of each pass of a small flow while an avalanche runs to
//! rest.
//!
//! A sub-step of a season's avalanche visits a few hundred to a few thousand cells (tens of
//! µs); a rayon fork and join wakes a sleeping worker, which costs as much as the half it would
//! take, so small flows ran on one core. For the length of a run the helper waits for work by
//! spinning, so a split costs well under a µs; after a longer wait it yields its core at each
//! look, and after a millisecond or so it sleeps until work is posted (a run paced by its
//! caller, as the editor's live avalanche is, keeps no core busy). The
//! passes split as they split on rayon's workers (blocks of rows, rows), each part writing only
//! its own rows and the sums taken in row order, so the results keep their bits.

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// Nothing to do.
const IDLE: u8 = 0;
/// A part is posted for the helper.
const POSTED: u8 = 1;
/// The helper finished its part.
const DONE: u8 = 2;

/// Spins before a waiting thread starts yielding its core at each look (tens of µs: the
/// serial work between two sub-steps).
const SPINS_BEFORE_YIELD: u32 = 1 << 11;

/// Looks (spins and yields) before the waiting helper sleeps until work is posted (a few ms).
const LOOKS_BEFORE_SLEEP: u32 = 1 << 13;

/// The work items `lo..hi` of one part: `f(item, worker)`.
struct Part {
    /// The caller's closure, its lifetime erased: [`TeamHandle::run`] does not return before
    /// the helper has finished with it.
    f: *const (dyn Fn(usize, usize) + Sync + 'static),
    lo: usize,
    hi: usize,
}

// SAFETY: the closure is `Sync` and outlives the part (see `Part::f`).
unsafe impl Send for Part {}

#[derive(Default)]
struct Shared {
    state: AtomicU8,
    stop: AtomicBool,
    /// The helper sleeps (parked): a poster wakes it.
    asleep: AtomicBool,
    helper: std::sync::OnceLock<std::thread::Thread>,
    part: Mutex<Option<Part>>,
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

/// The helper thread of one run; stopped and joined when dropped.
pub(crate) struct Team {
    shared: Arc<Shared>,
    helper: Option<JoinHandle<()>>,
}

impl Team {
    /// A helper thread when the run may use more than one thread (the rayon pool it runs in
    /// has several), else `None`.
    pub(crate) fn start() -> Option<Team> {
        if snowscape_terrain::parallel::workers() < 2 {
            return None;
        }
        let shared = Arc::new(Shared::default());
        let serving = Arc::clone(&shared);
        let helper = std::thread::Builder::new()
            .name("avalanche-helper".into())
            .spawn(move || serve(&serving))
            .ok()?;
        let _ = shared.helper.set(helper.thread().clone());
        Some(Team {
            shared,
            helper: Some(helper),
        })
    }

    /// A handle for the flow's scratch.
    pub(crate) fn handle(&self) -> TeamHandle {
        TeamHandle(Some(Arc::clone(&self.shared)))
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        if let Some(h) = self.helper.take() {
            h.thread().unpark();
            // A panic of the helper's own loop (not of a part: those are caught) has nothing
            // left to report.
            let _ = h.join();
        }
    }
}

/// The helper's loop: runs each posted part, then waits for the next.
fn serve(shared: &Shared) {
    let mut idle = 0u32;
    while !shared.stop.load(Ordering::Acquire) {
        if shared.state.load(Ordering::Acquire) != POSTED {
            idle = idle.saturating_add(1);
            if idle < SPINS_BEFORE_YIELD {
                std::hint::spin_loop();
            } else if idle < LOOKS_BEFORE_SLEEP {
                std::thread::yield_now();
            } else {
                // Announce the sleep, look once more (a part posted before the announcement
                // finds no sleeper to wake), then sleep; a timeout bounds any missed wake.
                shared.asleep.store(true, Ordering::SeqCst);
                if shared.state.load(Ordering::SeqCst) != POSTED
                    && !shared.stop.load(Ordering::SeqCst)
                {
                    std::thread::park_timeout(std::time::Duration::from_millis(5));
                }
                shared.asleep.store(false, Ordering::SeqCst);
            }
            continue;
        }
        idle = 0;
        let part = shared.part.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(Part { f, lo, hi }) = part {
            // SAFETY: the poster waits for DONE before the closure goes out of scope.
            let f = unsafe { &*f };
            if let Err(p) = catch_unwind(AssertUnwindSafe(|| {
                for i in lo..hi {
                    f(i, 1);
                }
            })) {
                *shared.panic.lock().unwrap_or_else(|e| e.into_inner()) = Some(p);
            }
        }
        shared.state.store(DONE, Ordering::Release);
    }
}

/// The scratch's handle on the run's team (none outside a run, or on one thread). A clone
/// has none: a copied scratch is a work buffer, not a run.
#[derive(Default)]
pub(crate) struct TeamHandle(Option<Arc<Shared>>);

impl Clone for TeamHandle {
    fn clone(&self) -> Self {
        Self(None)
    }
}

impl std::fmt::Debug for TeamHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "TeamHandle({})",
            if self.0.is_some() { "on" } else { "off" }
        )
    }
}

impl TeamHandle {
    /// Runs `caller` on the calling thread and `helper` on the helper at the same time (both
    /// on the calling thread, one after the other, without a helper); returns when both are
    /// done, re-raising a panic of either. Allocates nothing.
    pub(crate) fn join(&self, caller: impl FnOnce() + Send, helper: impl FnOnce() + Send) {
        fn call(f: &Mutex<Option<impl FnOnce()>>) {
            if let Some(f) = f.lock().unwrap_or_else(|e| e.into_inner()).take() {
                f();
            }
        }
        let (caller, helper) = (Mutex::new(Some(caller)), Mutex::new(Some(helper)));
        self.run(2, 1, &|i, _| {
            if i == 0 { call(&caller) } else { call(&helper) }
        });
    }

    /// Whether a helper is there.
    pub(crate) fn is_on(&self) -> bool {
        self.0.is_some()
    }

    /// Runs `f(item, worker)` for the items `0..n`: `0..mid` on the calling thread (worker 0)
    /// and `mid..n` on the helper (worker 1), at the same time; returns when both are done
    /// (re-raising a panic of the helper's part). Without a helper, all on the calling thread.
    pub(crate) fn run(&self, n: usize, mid: usize, f: &(dyn Fn(usize, usize) + Sync)) {
        let Some(shared) = &self.0 else {
            (0..n).for_each(|i| f(i, 0));
            return;
        };
        // (A panic left by a part whose caller panicked too has been reported by the latter.)
        shared
            .panic
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        let mid = mid.min(n);
        if mid == n {
            (0..n).for_each(|i| f(i, 0));
            return;
        }
        // SAFETY (lifetime erasure): `Wait` below does not let this function return, nor
        // unwind past it, before the helper has set DONE, after its last use of `f`.
        let erased: *const (dyn Fn(usize, usize) + Sync + 'static) =
            unsafe { std::mem::transmute(f as *const (dyn Fn(usize, usize) + Sync)) };
        *shared.part.lock().unwrap_or_else(|e| e.into_inner()) = Some(Part {
            f: erased,
            lo: mid,
            hi: n,
        });
        shared.state.store(POSTED, Ordering::SeqCst);
        if shared.asleep.load(Ordering::SeqCst)
            && let Some(t) = shared.helper.get()
        {
            t.unpark();
        }
        struct Wait<'a>(&'a Shared);
        impl Drop for Wait<'_> {
            fn drop(&mut self) {
                let mut looks = 0u32;
                while self.0.state.load(Ordering::Acquire) != DONE {
                    looks = looks.saturating_add(1);
                    if looks < SPINS_BEFORE_YIELD {
                        std::hint::spin_loop();
                    } else {
                        std::thread::yield_now();
                    }
                }
                self.0.state.store(IDLE, Ordering::Release);
            }
        }
        {
            let _wait = Wait(shared);
            (0..mid).for_each(|i| f(i, 0));
        }
        if let Some(p) = shared
            .panic
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        {
            resume_unwind(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    /// Runs `f` with the handle of a team started in a pool of two threads.
    fn with_team(f: impl FnOnce(&TeamHandle) + Send) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            let team = Team::start().expect("two threads");
            f(&team.handle());
        });
    }

    #[test]
    fn both_halves_run_once_on_their_workers() {
        with_team(|h| {
            for round in 0..200 {
                let hits: Vec<AtomicUsize> = (0..37).map(|_| AtomicUsize::new(0)).collect();
                let workers: Vec<AtomicUsize> = (0..37).map(|_| AtomicUsize::new(9)).collect();
                let mid = round % 38;
                if round % 50 == 0 {
                    // Long enough for the helper to fall asleep: the next part wakes it.
                    std::thread::sleep(std::time::Duration::from_millis(30));
                }
                h.run(37, mid, &|i, w| {
                    hits[i].fetch_add(1, Ordering::Relaxed);
                    workers[i].store(w, Ordering::Relaxed);
                });
                for i in 0..37 {
                    assert_eq!(hits[i].load(Ordering::Relaxed), 1);
                    let want = if i < mid || mid >= 37 { 0 } else { 1 };
                    assert_eq!(
                        workers[i].load(Ordering::Relaxed),
                        want,
                        "item {i} mid {mid}"
                    );
                }
            }
        });
        // One thread: no helper.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        assert!(one.install(Team::start).is_none());
    }

    #[test]
    fn a_panic_in_the_helpers_half_reaches_the_caller_after_both_halves() {
        with_team(|h| {
            let done = AtomicUsize::new(0);
            let r = catch_unwind(AssertUnwindSafe(|| {
                h.run(10, 5, &|i, _| {
                    if i == 7 {
                        panic!("item 7");
                    }
                    done.fetch_add(1, Ordering::Relaxed);
                })
            }));
            assert!(r.is_err());
            // The caller's half ran whole; the team still works.
            assert!(done.load(Ordering::Relaxed) >= 5);
            let count = AtomicUsize::new(0);
            h.run(10, 5, &|_, _| {
                count.fetch_add(1, Ordering::Relaxed);
            });
            assert_eq!(count.load(Ordering::Relaxed), 10);
        });
    }

    #[test]
    fn join_runs_each_part_once_the_second_on_the_helper() {
        with_team(|h| {
            let me = std::thread::current().id();
            for _ in 0..50 {
                let (mut a, mut b) = (None, None);
                h.join(
                    || a = Some(std::thread::current().id()),
                    || b = Some(std::thread::current().id()),
                );
                assert_eq!(a, Some(me));
                assert!(b.is_some() && b != Some(me));
            }
            // Without a helper both run on the calling thread.
            let (mut a, mut b) = (0, 0);
            TeamHandle::default().join(|| a += 1, || b += 1);
            assert_eq!((a, b), (1, 1));
        });
    }
}

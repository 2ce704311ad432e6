//! Issue 18, item 3: a flow allocates nothing per sub-step. Once a workspace's buffers have
//! grown to a flow's size (a first run of the same avalanche), a record interval (its
//! sub-steps, the entrainment, the record, the films settling) allocates nothing, on one
//! thread, on two (the run's helper thread) and on four (rayon's workers).
//!
//! Every allocation of the process is counted (this file holds one test, so the harness's
//! other threads are idle while it runs).

use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheWorkspace, ReleasedCells, RunOptions,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting allocations and reallocations.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A 38° slope onto flat ground, 5 m cells, 1 m of unstable snow over stable snow (which the
/// flow entrains).
fn slope() -> LayeredTerrain {
    let (w, h) = (120usize, 260usize);
    let g = GridGeometry::square(w, h, 5.0).unwrap();
    let tan = 38f64.to_radians().tan();
    let bed: Vec<f32> = (0..w * h)
        .map(|i| {
            let r = (i / w) as f64;
            (tan * 5.0 * (140.0 - r).max(0.0) + 0.01 * (i % w) as f64) as f32
        })
        .collect();
    let mut t = LayeredTerrain::from_bedrock(Grid::new(g, bed, NodataMask::all_valid()).unwrap());
    t.layer_mut(SnowLayer::Stable).fill(0.5);
    t
}

/// Allocations in each record interval (from the first record on) of the second of two runs
/// of the same avalanche through one workspace, on a pool of `threads`.
fn allocations_per_record(threads: usize) -> Vec<usize> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut t = slope();
        let w = t.geometry().width();
        let cells: Vec<usize> = (10..40)
            .flat_map(|r| (30..90).map(move |c| r * w + c))
            .collect();
        for &i in &cells {
            t.layer_mut(SnowLayer::Unstable)[i] = 1.0;
        }
        let mut ws = AvalancheWorkspace::new();
        let opts = RunOptions::default();
        let mut counts = Vec::with_capacity(10_000);
        for run in 0..2 {
            let mut terrain = t.clone();
            let mut last = None;
            ws.run_to_rest::<AvalancheError>(
                &mut terrain,
                ReleasedCells::new(&cells, None),
                &AvalancheParams::default(),
                &opts,
                SnowLayer::Stable,
                |_| {
                    let now = ALLOCATIONS.load(Ordering::SeqCst);
                    if run == 1
                        && let Some(before) = last
                    {
                        counts.push(now - before);
                    }
                    last = Some(ALLOCATIONS.load(Ordering::SeqCst));
                    Ok(())
                },
            )
            .unwrap();
        }
        counts
    })
}

#[test]
fn record_intervals_allocate_nothing_once_the_buffers_have_grown() {
    for threads in [1, 2, 4] {
        let counts = allocations_per_record(threads);
        assert!(
            counts.len() > 60,
            "the flow should run a while ({} records)",
            counts.len()
        );
        let total: usize = counts.iter().sum();
        let with: Vec<(usize, usize)> = counts
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(k, n)| (k + 1, *n))
            .collect();
        assert_eq!(
            total,
            0,
            "{threads} threads: {total} allocations in {} record intervals \
             (interval, allocations): {with:?}",
            counts.len()
        );
    }
}

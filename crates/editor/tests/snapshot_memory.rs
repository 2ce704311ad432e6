//! The memory of one timeline snapshot, measured with a counting allocator: the bytes a clone
//! of the season and its painted maps allocate, per grid cell, after a few days (when the
//! scratch buffers the steps use and the ski area are allocated), against the timeline's estimate
//! [`SNAPSHOT_BYTES_PER_CELL`], which must not be below it.

mod common;

use common::session;
use snowscape_editor::protocol::{BrushOp, BrushTarget, ClientMessage};
use snowscape_editor::timeline::SNAPSHOT_BYTES_PER_CELL;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts the bytes allocated (not freed) through it.
struct Counting;

static ALLOCATED: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATED.fetch_add(layout.size(), Ordering::SeqCst);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_snapshot_takes_at_most_the_estimated_bytes_per_cell() {
    for size in [128usize, 256] {
        let mut s = session(size, 20.0);
        // Snow, and a painted skier area (the season's ski area is made when skiers first
        // run), then a few days.
        for (stroke, target, strength) in [
            (1, BrushTarget::Unstable, 0.5),
            (2, BrushTarget::SkiArea, 1.0),
        ] {
            let c = size as f64 / 2.0;
            let dab = ClientMessage::Brush {
                stroke,
                op: BrushOp::Add,
                target,
                col: c,
                row: c,
                radius_m: 10.0 * size as f64,
                strength,
                value: 0.0,
            };
            s.handle(dab, None, None).expect("brush");
        }
        s.handle(ClientMessage::Step { days: 3.0 }, None, None)
            .expect("step");
        assert!(s.winter().ski_area().is_some(), "the skiers ran");
        let before = ALLOCATED.load(Ordering::SeqCst);
        let copy = (s.winter().clone(), s.paint().clone());
        let bytes = ALLOCATED.load(Ordering::SeqCst) - before;
        drop(copy);
        let per_cell = bytes as f64 / (size * size) as f64;
        println!("{size}²: one snapshot {bytes} bytes, {per_cell:.0} bytes per cell");
        assert!(
            per_cell <= SNAPSHOT_BYTES_PER_CELL as f64,
            "{size}²: {per_cell:.0} bytes per cell, estimate {SNAPSHOT_BYTES_PER_CELL}"
        );
        assert!(
            per_cell > SNAPSHOT_BYTES_PER_CELL as f64 / 4.0,
            "estimate far too high"
        );
    }
}

//! The memory of one timeline snapshot, per grid cell, after a few simulated days (when the
//! scratch buffers the steps use and the ski area are allocated): what a whole clone of the
//! season and its painted maps would take (the former snapshot, measured with a counting
//! allocator, for comparison) and what the packed snapshot takes, which must stay within
//! [`SNAPSHOT_BYTES_PER_CELL`] on a procedural terrain and on the avaMal DEM of
//! `../shared/data` (skipped when absent). Restoring a snapshot gives back the very bytes
//! that were stored, and the restored season continues as the original does.

mod common;

use common::session;
use snowscape_editor::Session;
use snowscape_editor::protocol::{BrushOp, BrushTarget, ClientMessage};
use snowscape_editor::timeline::SNAPSHOT_BYTES_PER_CELL;
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
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

fn checkpoint(w: &Winter) -> Vec<u8> {
    let mut b = Vec::new();
    w.write_checkpoint(&mut b).expect("checkpoint");
    b
}

/// Paints snow and a skier area, steps `days`, and checks the snapshot's size and restore.
fn measure(mut s: Session, label: &str, days: f64) {
    let g = s.terrain().geometry().clone();
    let (w, h) = (g.width(), g.height());
    let cells = (w * h) as f64;
    for (stroke, target, strength) in [
        (1, BrushTarget::Unstable, 0.5),
        (2, BrushTarget::SkiArea, 1.0),
    ] {
        let dab = ClientMessage::Brush {
            stroke,
            op: BrushOp::Add,
            target,
            col: w as f64 / 2.0,
            row: h as f64 / 2.0,
            radius_m: 0.3 * w.min(h) as f64 * g.cell_size_x(),
            strength,
            value: 0.0,
        };
        s.handle(dab, None, None).expect("brush");
    }
    s.handle(ClientMessage::Step { days }, None, None)
        .expect("step");
    let before = ALLOCATED.load(Ordering::SeqCst);
    let copy = (s.winter().clone(), s.paint().clone());
    let clone_bytes = ALLOCATED.load(Ordering::SeqCst) - before;
    drop(copy);
    let t = s.timeline();
    assert_eq!(t.len(), 2);
    let packed = t.snapshot_bytes(1).expect("the step's snapshot");
    let first = t.snapshot_bytes(0).expect("the first snapshot");
    let mean = (packed + first) as f64 / 2.0 / cells;
    println!(
        "{label}: a whole clone {:.0} bytes per cell; packed snapshot after {days} days {:.1} bytes per cell (the first {:.1}; mean {mean:.1}; {:.1} MiB)",
        clone_bytes as f64 / cells,
        packed as f64 / cells,
        first as f64 / cells,
        packed as f64 / (1u64 << 20) as f64
    );
    assert!(
        packed as f64 / cells <= SNAPSHOT_BYTES_PER_CELL as f64,
        "{label}: {:.1} bytes per cell, at most {SNAPSHOT_BYTES_PER_CELL}",
        packed as f64 / cells
    );
    assert!(t.bytes() <= packed + first + 1024);

    // Restore: the same bytes back, and the same season onwards.
    let original = s.winter().clone();
    let paint = s.paint().clone();
    let stored = checkpoint(&original);
    s.handle(ClientMessage::Seek { index: 0 }, None, None)
        .expect("seek to the first");
    assert_eq!(s.winter().day(), 0.0);
    s.handle(ClientMessage::Seek { index: 1 }, None, None)
        .expect("seek back");
    assert!(
        checkpoint(s.winter()) == stored,
        "{label}: restored bytes differ"
    );
    assert!(s.paint() == &paint, "{label}: restored paint differs");
    assert!(s.terrain().snow == original.terrain.snow);
    // Onwards as a season resumed from the same checkpoint (`snowscape run --resume`).
    let t = &original.terrain;
    let bedrock = t.to_grid(t.bedrock.clone()).expect("bedrock");
    let mut a = Winter::resume(
        original.scenario().clone(),
        LayeredTerrain::from_bedrock(bedrock),
        &mut stored.as_slice(),
    )
    .expect("resume");
    assert!(checkpoint(&a) == stored);
    let mut b = s.winter().clone();
    let mut o = original;
    for w in [&mut a, &mut b, &mut o] {
        snowscape_editor::painted::set_painted_release(w, &paint).expect("paint");
        w.run_until(days + 1.0).expect("a day on");
    }
    println!(
        "{label}: a day on, restored = resumed: {}, restored = never stored: {}",
        checkpoint(&a) == checkpoint(&b),
        checkpoint(&o) == checkpoint(&b)
    );
    assert!(
        checkpoint(&a) == checkpoint(&b),
        "{label}: the restored season continues otherwise than a resumed one"
    );
}

#[test]
fn a_packed_snapshot_takes_at_most_its_bytes_per_cell_and_restores_exactly() {
    measure(session(256, 20.0), "256² procedural", 3.0);
}

#[test]
fn a_packed_snapshot_of_the_avamal_dem_takes_at_most_its_bytes_per_cell() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/dem/avaframe_avaMal/avaMal.asc");
    if !path.is_file() {
        println!("skipped: no {}", path.display());
        return;
    }
    let bedrock = snowscape_io::read_terrain(&path, &Default::default()).expect("avaMal");
    let scenario = Scenario {
        seed: 3,
        days: 20.0,
        ..Scenario::default()
    };
    let winter = Winter::new(scenario, LayeredTerrain::from_bedrock(bedrock)).expect("winter");
    measure(Session::new(winter, "avaMal"), "avaMal 567x787", 2.0);
}

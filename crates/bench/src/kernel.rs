//! A benchmarked kernel and its measured throughput.
//!
//! A [`Kernel`] owns its inputs and scratch buffers (set up once, not timed) and a closure that
//! runs one call. [`measure`] runs it once to warm up, then `repeats` times, and reports the
//! median time per call, cells per second, and the memory traffic its `bytes_per_cell` model
//! implies, as GB/s and as a fraction of the machine's copy bandwidth.

use serde::{Deserialize, Serialize};
use std::time::Instant;
use thiserror::Error;

/// Why one call of a kernel failed.
#[derive(Debug, Error)]
pub enum KernelError {
    /// The terrain model rejected an input.
    #[error(transparent)]
    Terrain(#[from] snowscape_terrain::TerrainError),
    /// Reading or writing a raster failed.
    #[error(transparent)]
    Raster(#[from] snowscape_io::RasterError),
    /// Rendering failed.
    #[error(transparent)]
    Render(#[from] snowscape_render::RenderError),
    /// The environment precompute failed.
    #[error(transparent)]
    Environment(#[from] snowscape_environment::EnvironmentError),
    /// A season phenomenon step failed.
    #[error(transparent)]
    Phenomenon(#[from] snowscape_season::phenomenon::PhenomenonError),
    /// A season run failed.
    #[error(transparent)]
    Season(#[from] snowscape_season::winter::SeasonError),
    /// An avalanche step failed.
    #[error(transparent)]
    Avalanche(#[from] snowscape_avalanche::AvalancheError),
    /// A physical-transport stage failed.
    #[error(transparent)]
    Transport(Box<snowscape_transport::TransportError>),
    /// A release area could not be read.
    #[error(transparent)]
    ReleaseArea(#[from] snowscape_avalanche::ReleaseAreaError),
    /// Real data a benchmark needs is missing (the shared data folder beside the checkout).
    #[error("{0} is missing: this benchmark needs the shared data folder beside the checkout")]
    MissingData(String),
    /// A file-system operation (temporary directory) failed.
    #[error("{what}: {source}")]
    Io {
        what: &'static str,
        source: std::io::Error,
    },
}

/// One call of a kernel.
pub type KernelFn = Box<dyn FnMut() -> Result<(), KernelError> + Send>;

/// A kernel ready to run: a name, the cells one call processes, its memory-traffic model and
/// the call itself.
pub struct Kernel {
    /// Name in reports, e.g. `terrain/slopes`.
    pub name: String,
    /// Cells one call processes.
    pub cells: usize,
    /// Bytes of memory traffic per cell of one call (reads plus writes, documented where the
    /// kernel is built).
    pub bytes_per_cell: f64,
    /// One call.
    pub run: KernelFn,
}

impl Kernel {
    /// A kernel from its parts.
    pub fn new(
        name: impl Into<String>,
        cells: usize,
        bytes_per_cell: f64,
        run: impl FnMut() -> Result<(), KernelError> + Send + 'static,
    ) -> Self {
        Self {
            name: name.into(),
            cells,
            bytes_per_cell,
            run: Box::new(run),
        }
    }
}

impl std::fmt::Debug for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kernel")
            .field("name", &self.name)
            .field("cells", &self.cells)
            .field("bytes_per_cell", &self.bytes_per_cell)
            .finish_non_exhaustive()
    }
}

/// The measured throughput of one kernel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KernelResult {
    /// Kernel name.
    pub name: String,
    /// Cells one call processes.
    pub cells: usize,
    /// Median time of one call, seconds.
    pub seconds: f64,
    /// Cells per second at the median time.
    pub cells_per_s: f64,
    /// Memory traffic model, bytes per cell.
    pub bytes_per_cell: f64,
    /// Memory traffic at the median time, GB/s (10⁹ bytes per second).
    pub gb_per_s: f64,
    /// `gb_per_s` over the machine's copy bandwidth: 1 means the kernel runs at the memory
    /// limit; far below 1, it is bound by computation (or by something else than memory).
    pub bandwidth_fraction: f64,
}

/// A kernel that failed, and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct KernelFailure {
    /// Kernel name.
    pub name: String,
    /// The error message.
    pub reason: String,
}

/// Median of `times` (the mean of the two middle values for an even count).
pub fn median(times: &mut [f64]) -> f64 {
    if times.is_empty() {
        return f64::NAN;
    }
    times.sort_by(f64::total_cmp);
    let n = times.len();
    if n % 2 == 1 {
        times[n / 2]
    } else {
        0.5 * (times[n / 2 - 1] + times[n / 2])
    }
}

/// Runs `kernel` once to warm up, then `repeats` (at least 1) timed calls; throughput at the
/// median time, bandwidth relative to `copy_bandwidth_gb_s`.
pub fn measure(
    kernel: &mut Kernel,
    repeats: usize,
    copy_bandwidth_gb_s: f64,
) -> Result<KernelResult, KernelFailure> {
    let name = kernel.name.clone();
    let fail = |e: KernelError| KernelFailure {
        name: name.clone(),
        reason: e.to_string(),
    };
    (kernel.run)().map_err(fail)?;
    let mut times = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        (kernel.run)().map_err(fail)?;
        times.push(start.elapsed().as_secs_f64());
    }
    // A call faster than the clock's resolution still gets a finite rate.
    let seconds = median(&mut times).max(1e-9);
    let cells_per_s = kernel.cells as f64 / seconds;
    let gb_per_s = cells_per_s * kernel.bytes_per_cell / 1e9;
    Ok(KernelResult {
        name: kernel.name.clone(),
        cells: kernel.cells,
        seconds,
        cells_per_s,
        bytes_per_cell: kernel.bytes_per_cell,
        gb_per_s,
        bandwidth_fraction: gb_per_s / copy_bandwidth_gb_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&mut []).is_nan());
    }

    #[test]
    fn measure_counts_calls_and_derives_rates() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let calls = std::sync::Arc::new(AtomicUsize::new(0));
        let counter = calls.clone();
        let mut k = Kernel::new("count", 1000, 8.0, move || {
            counter.fetch_add(1, Ordering::Relaxed);
            std::thread::sleep(std::time::Duration::from_millis(1));
            Ok(())
        });
        let r = measure(&mut k, 3, 10.0).unwrap();
        assert_eq!(
            calls.load(Ordering::Relaxed),
            4,
            "one warm-up and three timed calls"
        );
        assert!((r.cells_per_s * r.seconds - 1000.0).abs() < 1e-6);
        assert!((r.gb_per_s - r.cells_per_s * 8.0 / 1e9).abs() < 1e-12);
        assert!((r.bandwidth_fraction - r.gb_per_s / 10.0).abs() < 1e-12);
    }

    #[test]
    fn a_failing_kernel_is_reported_by_name() {
        let mut k = Kernel::new("broken", 1, 1.0, || {
            Err(KernelError::Io {
                what: "test",
                source: std::io::Error::other("disk full"),
            })
        });
        let f = measure(&mut k, 2, 1.0).unwrap_err();
        assert_eq!(f.name, "broken");
        assert!(f.reason.contains("disk full"));
    }
}

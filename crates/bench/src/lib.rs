//! # snowscape-bench: how fast snowscape's kernels run on this machine
//!
//! [`run`] measures the machine's copy bandwidth ([`measure_copy_bandwidth`]), then every
//! kernel of the [`registry`] on a procedural alpine terrain of `size`² cells: the median time
//! per call after one warm-up, cells per second, and the memory traffic implied by each
//! kernel's bytes-per-cell model, in GB/s and as a fraction of the copy bandwidth (`docs/src/architecture.md#performance-and-benchmarks`:
//! that fraction says how close to the hardware limit a kernel is). The
//! [`BenchReport`] serialises to JSON (`snowscape bench` writes it as `bench.json`).
//!
//! The same registry runs under criterion: `cargo bench -p snowscape-bench` (grid side from
//! the `SNOWSCAPE_BENCH_SIZE` environment variable, default 256).

pub mod bandwidth;
pub mod kernel;
pub mod machine;
pub mod registry;
pub mod stencil;

pub use bandwidth::measure_copy_bandwidth;
pub use kernel::{Kernel, KernelError, KernelFailure, KernelResult, measure};
pub use machine::MachineInfo;

use serde::{Deserialize, Serialize};

/// Smallest grid side [`run`] uses, cells.
pub const MIN_SIZE: usize = 16;
/// Largest grid side [`run`] uses, cells.
pub const MAX_SIZE: usize = 16_384;
/// Size of each of the two buffers of the copy-bandwidth measurement, bytes (256 MiB: far
/// beyond any cache).
pub const COPY_BYTES: usize = 256 << 20;

/// What to measure.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct BenchConfig {
    /// Cells per side of the benchmark terrain; clamped to 16..=16384. Default 1024 (the
    /// interactive size the project targets).
    pub size: usize,
    /// Timed calls per kernel after the warm-up; at least 1. Default 5.
    pub repeats: usize,
    /// Rayon threads; `None` uses the global pool (one thread per logical CPU). Default `None`.
    pub threads: Option<usize>,
    /// Only the kernels whose name starts with this (e.g. `avalanche/`); `None` runs all.
    pub only: Option<String>,
}

impl Default for BenchConfig {
    fn default() -> Self {
        Self {
            size: 1024,
            repeats: 5,
            threads: None,
            only: None,
        }
    }
}

/// The measurements of one [`run`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// The machine.
    pub machine: MachineInfo,
    /// Copy bandwidth, GB/s (read plus write traffic, best of the repeats).
    pub copy_bandwidth_gb_s: f64,
    /// Cells per side of the benchmark terrain.
    pub size: usize,
    /// Timed calls per kernel.
    pub repeats: usize,
    /// One result per kernel that ran.
    pub kernels: Vec<KernelResult>,
    /// Kernels that could not be set up or failed, with the reason.
    pub failures: Vec<KernelFailure>,
}

impl BenchReport {
    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Serialising plain numbers, strings and vectors cannot fail; non-finite floats are
        // written as null by serde_json.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// Measures the copy bandwidth and every kernel at `config.size`², in a rayon pool of
/// `config.threads` threads when given. `on_progress` receives one line per step, on the
/// calling thread.
pub fn run(config: &BenchConfig, mut on_progress: impl FnMut(&str)) -> BenchReport {
    let pool = config.threads.and_then(|n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| on_progress(&format!("thread pool of {n}: {e}; using the global pool")))
            .ok()
    });
    let in_pool = |work: &mut (dyn FnMut() + Send)| match &pool {
        Some(p) => p.install(work),
        None => work(),
    };
    let size = config.size.clamp(MIN_SIZE, MAX_SIZE);
    let repeats = config.repeats.max(1);
    let mut machine = MachineInfo::current();
    in_pool(&mut || machine.threads = rayon::current_num_threads());
    on_progress(&format!(
        "{} threads on {}",
        machine.threads,
        machine.cpu_model.as_deref().unwrap_or("an unknown CPU")
    ));
    let mut copy_bandwidth_gb_s = 0.0;
    in_pool(&mut || copy_bandwidth_gb_s = measure_copy_bandwidth(COPY_BYTES, repeats.max(3)));
    on_progress(&format!("copy bandwidth: {copy_bandwidth_gb_s:.1} GB/s"));
    let mut report = BenchReport {
        machine,
        copy_bandwidth_gb_s,
        size,
        repeats,
        kernels: Vec::new(),
        failures: Vec::new(),
    };
    on_progress(&format!("setting up the kernels at {size}x{size}"));
    let mut kernels = Err(KernelError::Io {
        what: "setting up the kernels",
        source: std::io::Error::other("not run"),
    });
    in_pool(&mut || kernels = registry::kernels_matching(size, config.only.as_deref()));
    let kernels = match kernels {
        Ok(k) => k,
        Err(e) => {
            on_progress(&format!("setup failed: {e}"));
            report.failures.push(KernelFailure {
                name: "setup".into(),
                reason: e.to_string(),
            });
            return report;
        }
    };
    for mut kernel in kernels {
        let mut outcome = None;
        in_pool(&mut || outcome = Some(measure(&mut kernel, repeats, copy_bandwidth_gb_s)));
        match outcome {
            Some(Ok(r)) => {
                on_progress(&format!(
                    "{}: {:.3} ms, {:.3e} cells/s, {:.2} GB/s ({:.0} % of copy bandwidth)",
                    r.name,
                    r.seconds * 1e3,
                    r.cells_per_s,
                    r.gb_per_s,
                    100.0 * r.bandwidth_fraction
                ));
                report.kernels.push(r);
            }
            Some(Err(f)) => {
                on_progress(&format!("{} failed: {}", f.name, f.reason));
                report.failures.push(f);
            }
            None => {}
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_sets_up_and_runs_the_kernels_named() {
        let config = BenchConfig {
            size: 32,
            repeats: 1,
            threads: Some(1),
            only: Some("avalanche/slope".into()),
        };
        let report = run(&config, |_| {});
        assert!(report.failures.is_empty(), "{:?}", report.failures);
        let names: Vec<&str> = report.kernels.iter().map(|k| k.name.as_str()).collect();
        assert_eq!(names, ["avalanche/slope_run_to_rest"]);
        // A kernel of the season set up apart from the season's others (the snowpack's).
        for name in ["season/enhanced_melt", "season/slope_shedding"] {
            let report = run(
                &BenchConfig {
                    only: Some(name.into()),
                    ..config.clone()
                },
                |_| {},
            );
            let names: Vec<&str> = report.kernels.iter().map(|k| k.name.as_str()).collect();
            assert_eq!(names, [name], "{:?}", report.failures);
        }
    }

    #[test]
    fn a_small_run_measures_every_kernel_and_serialises() {
        let config = BenchConfig {
            size: 64,
            repeats: 1,
            threads: Some(2),
            only: None,
        };
        let mut lines = Vec::new();
        let report = run(&config, |l| lines.push(l.to_string()));
        assert!(report.failures.is_empty(), "{:?}", report.failures);
        let names: Vec<&str> = report.kernels.iter().map(|k| k.name.as_str()).collect();
        for expected in [
            "terrain/alpine",
            "terrain/normals",
            "terrain/slopes",
            "terrain/laplacian_reference",
            "terrain/resample_bilinear",
            "io/geotiff_round_trip",
            "render/preview",
            "transport/step",
            "transport/wind_iteration",
            "transport/flakes",
            "season/hazard_map",
            "avalanche/substep",
            "avalanche/slope_run_to_rest",
            "avalanche/avakot_run_to_rest",
        ] {
            assert!(
                names.contains(&expected),
                "{expected} missing from {names:?}"
            );
        }
        assert!(report.copy_bandwidth_gb_s.is_finite() && report.copy_bandwidth_gb_s > 0.0);
        for k in &report.kernels {
            for v in [k.seconds, k.cells_per_s] {
                assert!(v.is_finite() && v > 0.0, "{}: {v}", k.name);
            }
            // A kernel without a memory-traffic model (bytes per cell 0, such as a season whose
            // avalanche cost follows their footprints) reports no bandwidth; every other does.
            for v in [k.gb_per_s, k.bandwidth_fraction] {
                if k.bytes_per_cell > 0.0 {
                    assert!(v.is_finite() && v > 0.0, "{}: {v}", k.name);
                } else {
                    assert_eq!(v, 0.0, "{}", k.name);
                }
            }
            assert!(k.cells > 0);
        }
        let unmodelled: Vec<&str> = report
            .kernels
            .iter()
            .filter(|k| k.bytes_per_cell == 0.0)
            .map(|k| k.name.as_str())
            .collect();
        assert_eq!(
            unmodelled,
            [
                "season/100_days_with_avalanches",
                "avalanche/slope_run_to_rest",
                "avalanche/avakot_run_to_rest",
                "transport/flakes"
            ]
        );
        assert_eq!(report.machine.threads, 2);
        assert_eq!(report.size, 64);
        assert!(lines.len() > report.kernels.len());
        let json = report.to_json();
        let back: BenchReport = serde_json::from_str(&json).unwrap();
        assert_eq!(back.machine, report.machine);
        assert_eq!(back.kernels.len(), report.kernels.len());
        for (b, k) in back.kernels.iter().zip(&report.kernels) {
            assert_eq!(b.name, k.name);
            assert!((b.cells_per_s / k.cells_per_s - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn out_of_range_configs_are_clamped() {
        let report = run(
            &BenchConfig {
                size: 0,
                repeats: 0,
                threads: Some(1),
                only: None,
            },
            |_| {},
        );
        assert_eq!(report.size, MIN_SIZE);
        assert_eq!(report.repeats, 1);
    }
}

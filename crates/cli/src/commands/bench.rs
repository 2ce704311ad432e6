//! `snowscape bench`: machine memory bandwidth and kernel throughput, written to bench.json.

use crate::cli::{BenchArgs, GlobalArgs};
use crate::failure::{ExitCodeExt, Failure};
use crate::stdout::outln;
use anyhow::anyhow;
use snowscape_bench::{BenchConfig, run as run_bench};
use snowscape_io::write_bytes_atomic;

pub fn run(args: &BenchArgs, global: &GlobalArgs) -> Result<(), Failure> {
    if !(16..=16384).contains(&args.size) {
        return Err(anyhow!(
            "--size must be within 16..=16384 cells, got {}",
            args.size
        ))
        .bad_input();
    }
    if args.repeats == 0 {
        return Err(anyhow!("--repeats must be at least 1")).bad_input();
    }
    let config = BenchConfig {
        size: args.size,
        repeats: args.repeats,
        threads: global.threads,
        only: args.only.clone(),
    };
    let quiet = global.quiet;
    let report = run_bench(&config, |msg| {
        if !quiet {
            eprintln!("bench: {msg}");
        }
    });
    let json = serde_json::to_vec_pretty(&report).job_failed()?;
    write_bytes_atomic(&args.out, &json).job_failed()?;
    if !quiet {
        outln!(
            "copy bandwidth {:.2} GB/s; grid {}², {} repeats",
            report.copy_bandwidth_gb_s,
            report.size,
            args.repeats
        );
        outln!(
            "{:<28} {:>14} {:>12} {:>10} {:>8}",
            "kernel",
            "cells/s",
            "ms/call",
            "GB/s",
            "of bw"
        );
        for k in &report.kernels {
            outln!(
                "{:<28} {:>14.3e} {:>12.3} {:>10.2} {:>7.1}%",
                k.name,
                k.cells_per_s,
                k.seconds * 1e3,
                k.gb_per_s,
                100.0 * k.bandwidth_fraction
            );
        }
        outln!("wrote {}", args.out.display());
    }
    Ok(())
}

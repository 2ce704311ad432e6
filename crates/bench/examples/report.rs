//! Runs the benchmark and prints the JSON report:
//! `cargo run --release -p snowscape-bench --example report -- [size] [repeats] [threads]
//! [name prefix]`.

use snowscape_bench::{BenchConfig, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let defaults = BenchConfig::default();
    let config = BenchConfig {
        size: args.get(1).map_or(Ok(defaults.size), |s| s.parse())?,
        repeats: args.get(2).map_or(Ok(defaults.repeats), |s| s.parse())?,
        threads: args.get(3).map(|s| s.parse()).transpose()?,
        only: args.get(4).cloned(),
    };
    let report = run(&config, |line| eprintln!("{line}"));
    println!("{}", report.to_json());
    Ok(())
}

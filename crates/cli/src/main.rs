//! `snowscape`: the command-line front end.
//!
//! Exit codes: 0 success; 1 the job failed (an output could not be written, an internal error);
//! 2 bad input (a usage error, an unreadable or invalid file, an invalid parameter).

mod bounds;
mod cli;
mod commands;
mod dem_input;
mod failure;
mod outputs;
mod pairs;
mod progress;
mod report;
mod validation;

use clap::Parser;
use failure::Failure;
use std::process::ExitCode;

fn main() -> ExitCode {
    // First: a CPU without what the build assumes would die on an illegal instruction.
    let missing = snowscape::cpu::missing_features();
    if !missing.is_empty() {
        eprintln!("error: {}", snowscape::cpu::requirement_message(&missing));
        return ExitCode::from(1);
    }
    let args = cli::Cli::parse();
    init_logging(args.global.quiet, args.global.verbose);
    if let Some(n) = args.global.threads {
        if let Err(e) = bounds::check_threads(n) {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("error: cannot start {n} worker threads: {e}");
            return ExitCode::from(1);
        }
    }
    // The whole command runs on a worker of the pool: its parallel loops then fork and join
    // inside the pool instead of each one handing its work over from the main thread and
    // sleeping until it is done (thousands of times per avalanche).
    match rayon::scope(|_| commands::dispatch(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure { code, error }) => {
            eprintln!("error: {error}");
            // Error types that print their source inside their own message ("checkpoint:
            // {0}") would repeat it: a cause already said by the line above is skipped.
            let mut said = error.to_string();
            for cause in error.chain().skip(1) {
                let text = cause.to_string();
                if !said.contains(&text) {
                    eprintln!("  caused by: {text}");
                }
                said = text;
            }
            ExitCode::from(code)
        }
    }
}

fn init_logging(quiet: bool, verbose: u8) {
    let level = match (quiet, verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("SNOWSCAPE_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .init();
}

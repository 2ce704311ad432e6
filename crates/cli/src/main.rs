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
mod stdout;

use clap::Parser;
use failure::Failure;
use snowscape::messages::clip_values;
use std::io::IsTerminal;
use std::process::ExitCode;

fn main() -> ExitCode {
    // First: a CPU without what the build assumes would die on an illegal instruction.
    let missing = snowscape::cpu::missing_features();
    if !missing.is_empty() {
        eprintln!("error: {}", snowscape::cpu::requirement_message(&missing));
        return ExitCode::from(1);
    }
    let args = match cli::Cli::try_parse() {
        Ok(args) => args,
        // A usage error quoting a huge argument is clipped like every other message; short
        // ones (and --help, --version) go out as clap styles them.
        Err(e) if e.use_stderr() && e.to_string().len() > 1000 => {
            eprint!("{}", clip_values(&e.to_string()));
            return ExitCode::from(failure::BAD_INPUT);
        }
        Err(e) => e.exit(),
    };
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
            // Every value the messages echo is clipped to ~80 characters (a 10 MB scenario
            // value is named, not copied out whole).
            eprintln!("error: {}", clip_values(&error.to_string()));
            // Error types that print their source inside their own message ("checkpoint:
            // {0}") would repeat it: a cause already said by the line above is skipped.
            let mut said = error.to_string();
            for cause in error.chain().skip(1) {
                let text = cause.to_string();
                if !said.contains(&text) {
                    eprintln!("  caused by: {}", clip_values(&text));
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
    // Colour codes only for a terminal: in a log file or a pipe they are noise (`\x1b[33m`).
    let ansi = stderr_wants_colour(
        std::io::stderr().is_terminal(),
        std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty()),
    );
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(ansi)
        .with_target(false)
        .init();
}

/// Whether log lines on stderr get ANSI colours: only on a terminal, and not with `NO_COLOR`.
fn stderr_wants_colour(is_terminal: bool, no_color: bool) -> bool {
    is_terminal && !no_color
}

//! Writing to stdout without dying on a closed pipe.
//!
//! `println!` panics when stdout is a pipe whose reader has gone (`snowscape parameters |
//! head`: EPIPE, since Rust ignores SIGPIPE). Every command prints through [`outln!`] and
//! [`out!`] instead: the first broken pipe marks stdout closed and every later write is
//! dropped, quietly, while the command goes on (its files are its real output) and exits as it
//! would have. Other write errors are dropped the same way: nothing the command prints on
//! stdout is worth failing a finished job over.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

static CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes `args` to stdout unless it has been found closed.
pub fn write(args: std::fmt::Arguments<'_>) {
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if out.write_fmt(args).and_then(|()| out.flush()).is_err() {
        CLOSED.store(true, Ordering::Relaxed);
    }
}

/// `print!` that survives a closed stdout.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!($($arg)*))
    };
}

/// `println!` that survives a closed stdout.
macro_rules! outln {
    () => {
        $crate::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

pub(crate) use {out, outln};

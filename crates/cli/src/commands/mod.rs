//! One module per verb; [`dispatch`] is the only entry point.

mod avalanche;
mod bench;
mod convert;
pub mod cover;
mod demo;
mod export;
mod info;
mod parameters;
mod render;
mod run;
mod season;
mod serve;
mod transport;
mod validate;

use crate::cli::{Cli, Command};
use crate::failure::Failure;

/// Runs the command the user asked for.
pub fn dispatch(cli: Cli) -> Result<(), Failure> {
    let g = &cli.global;
    match &cli.command {
        Command::Demo(a) => demo::run(a, g),
        Command::Run(a) => run::run(a, g),
        Command::Info(a) => info::run(a),
        Command::Parameters(a) => parameters::run(a),
        Command::Render(a) => render::run(a, g),
        Command::Convert(a) => convert::run(a, g),
        Command::Bench(a) => bench::run(a, g),
        Command::Avalanche(a) => avalanche::run(a, g),
        Command::Serve(a) => serve::run(a, g),
        Command::Cover(a) => cover::run(a, g),
        Command::Transport(a) => transport::run_command(a, g),
        Command::Validate(a) => validate::run(a, g),
        Command::Export(a) => export::run(a, g),
    }
}

//! The `nephele` command line: parses, calls a stage, reports.

mod cli;

/// mimalloc keeps freed pages: the matrix products allocate packing buffers on every call,
/// and with the system allocator each of them costs fresh page faults.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use clap::{CommandFactory, FromArgMatches};
use std::process::ExitCode;

fn main() -> ExitCode {
    let matches = match cli::Cli::command().try_get_matches() {
        Ok(m) => m,
        Err(e) => return cli::parse_error(e),
    };
    let result = cli::Cli::from_arg_matches(&matches)
        .map_err(anyhow::Error::from)
        .and_then(|args| cli::run(args, &matches));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<cli::interrupt::Interrupted>() => {
            eprintln!("{e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

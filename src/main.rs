//! The `nephele` command line: parses, calls a stage, reports.

mod cli;

/// mimalloc keeps freed pages: the matrix products allocate packing buffers on every call,
/// and with the system allocator each of them costs fresh page faults.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

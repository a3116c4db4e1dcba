//! Ctrl-C during a path-traced render: the first SIGINT asks the render to stop after the rows
//! under way, so the samples already taken are written; a second one ends the process at once.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the first SIGINT.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// A render stopped by Ctrl-C, after writing what it had: the process exits 130, as a shell
/// reports a command ended by SIGINT.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

extern "C" fn on_sigint(_: libc::c_int) {
    STOP.store(true, Ordering::Relaxed);
    // Only async-signal-safe calls here: the next Ctrl-C takes the default action.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// Routes the next SIGINT to [`STOP`].
pub fn catch() {
    let handler: extern "C" fn(libc::c_int) = on_sigint;
    unsafe {
        libc::signal(libc::SIGINT, handler as libc::sighandler_t);
    }
}

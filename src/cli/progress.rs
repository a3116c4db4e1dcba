//! Progress on stderr: one look for every command's bars and spinners.

use indicatif::{ProgressBar, ProgressFinish, ProgressStyle};

/// A bar on stderr over `len` units of work: "PREFIX [███░░░] 42% MSG (elapsed, eta)". Like
/// every bar here it is hidden when stderr is not a terminal, so scripts and tests see only
/// the lines they expect.
pub(super) fn work_bar(prefix: &str, len: u64) -> ProgressBar {
    let style = ProgressStyle::with_template(
        "{prefix} [{bar:30}] {percent:>3}% {msg} ({elapsed}, eta {eta})",
    )
    .expect("static template");
    ProgressBar::new(len)
        .with_style(style)
        .with_prefix(prefix.to_string())
        .with_finish(ProgressFinish::AndClear)
}

/// A spinner on stderr for a step of unknown length: "⠋ PREFIX: MSG (elapsed)".
pub(super) fn spinner(prefix: &str, msg: &str) -> ProgressBar {
    let style = ProgressStyle::with_template("{spinner} {prefix}: {msg} ({elapsed})")
        .expect("static template");
    // Cleared when dropped: an error line then stands alone.
    let bar = ProgressBar::new_spinner()
        .with_style(style)
        .with_prefix(prefix.to_string())
        .with_finish(ProgressFinish::AndClear)
        .with_message(msg.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}
